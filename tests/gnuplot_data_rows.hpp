#pragma once
// The numbers of a gnuplot data file as the report wrote it, for tests that check a plot by what it
// was drawn from.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace mhb::testing {

// Rows of numbers, comment lines and blank lines left out; a row stops at its first field that is
// not a number (a quoted label).
inline std::vector<std::vector<double>> data_rows(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::vector<std::vector<double>> out;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        std::vector<double> row;
        for (double v; fields >> v;) row.push_back(v);
        out.push_back(row);
    }
    return out;
}

}  // namespace mhb::testing

#pragma once
// Comparing the tables of two runs of one experiment.
#include <sstream>
#include <string>
#include <vector>

namespace mhb::testing {

// table.csv without the run-time columns, which are the only ones allowed to differ between runs.
inline std::string without_times(const std::string& csv) {
    std::stringstream in(csv);
    std::string line, out;
    std::vector<bool> keep;
    bool header = true;
    while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::stringstream ls(line);
        std::string cell;
        while (std::getline(ls, cell, ',')) cells.push_back(cell);
        if (header) {
            for (const auto& c : cells) keep.push_back(c.find("time") == std::string::npos);
            header = false;
        }
        for (std::size_t i = 0; i < cells.size(); ++i)
            if (i < keep.size() && keep[i]) out += cells[i] + ",";
        out += "\n";
    }
    return out;
}

}  // namespace mhb::testing

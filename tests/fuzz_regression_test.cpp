#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/fuzz/input_formats.hpp"

namespace fs = std::filesystem;
using mhb::fuzz::Verdict;

namespace {

const fs::path regressions_directory = fs::path(MHBENCH_SOURCE_DIR) / "tests" / "fuzz" / "regressions";

std::string file_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in);
    return {std::istreambuf_iterator<char>(in), {}};
}

// Sorted, so a failure names the same file first on every machine.
std::vector<fs::path> files_in(const fs::path& directory) {
    std::vector<fs::path> out;
    if (fs::is_directory(directory))
        for (const auto& entry : fs::directory_iterator(directory))
            if (entry.is_regular_file()) out.push_back(entry.path());
    std::sort(out.begin(), out.end());
    return out;
}

Verdict verdict_on(const std::string& format, const std::string& file) {
    return mhb::fuzz::accept_or_refuse(mhb::fuzz::input_format(format),
                                       file_bytes(regressions_directory / format / file));
}

}  // namespace

TEST_CASE("every fuzzer regression file is accepted or refused with an input error", "[fuzz]") {
    std::size_t replayed = 0;
    for (const auto& format : mhb::fuzz::input_formats())
        for (const auto& file : files_in(regressions_directory / format.name)) {
            INFO(file.string());
            // Anything but an input error escapes accept_or_refuse and fails here with its message.
            CHECK_NOTHROW(mhb::fuzz::accept_or_refuse(format, file_bytes(file)));
            ++replayed;
        }
    CHECK(replayed >= 6);
}

TEST_CASE("every regression directory is the name of an input format", "[fuzz]") {
    // A misspelt directory would otherwise be skipped without a word.
    for (const auto& entry : fs::directory_iterator(regressions_directory)) {
        INFO(entry.path().string());
        CHECK(entry.is_directory());
        CHECK_NOTHROW(mhb::fuzz::input_format(entry.path().filename().string()));
    }
}

TEST_CASE("the bad inputs named in issue 12 are refused, not accepted", "[fuzz]") {
    CHECK(verdict_on("simulation_profile", "integer_beyond_2_pow_53_rs.toml") == Verdict::refused);
    CHECK(verdict_on("simulation_profile", "integer_beyond_2_pow_53_speed.toml") == Verdict::refused);
    CHECK(verdict_on("measurement", "semicolon_separated.csv") == Verdict::refused);
    CHECK(verdict_on("measurement", "decimal_comma.csv") == Verdict::refused);
    CHECK(verdict_on("measurement", "binary_bytes.csv") == Verdict::refused);
    CHECK(verdict_on("experiment", "empty.toml") == Verdict::refused);
}

TEST_CASE("an experiment whose lists multiply into 10^8 variants is refused before they are expanded", "[fuzz]") {
    CHECK(verdict_on("experiment", "grid_of_10_pow_8_variants.toml") == Verdict::refused);
}

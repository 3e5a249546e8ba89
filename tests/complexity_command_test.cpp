// `mhbench complexity`: the CEC reports' T0, T1, T2 table. Times are never compared with a number;
// the table's arithmetic, its rows and the refusals are.
#include <catch2/catch.hpp>

#include <regex>
#include <sstream>
#include <string>

#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb::testing;

TEST_CASE("complexity prints T0, T1, T2 and (T2 - T1)/T0 per optimizer and dimension", "[cli][complexity]") {
    TemporaryDirectory dir;
    const auto run = run_mhbench({"complexity", "lshade", "gwo", "--suite", "cec2022", "--evaluations", "3000", "--runs", "2",
                                  "--t0-iterations", "20000"},
                                 dir.path() / "log");
    REQUIRE(run.exit_code == 0);
    CHECK_THAT(run.output, Catch::Contains("3000 evaluations of cec2022_f1, T2 the mean of 2 runs"));
    const std::regex row(R"(\| (\w+) \| (\d+) \| ([0-9.]+) \| ([0-9.]+) \| ([0-9.]+) \| (-?[0-9.]+) \|)");
    std::istringstream lines(run.output);
    std::vector<std::string> seen;
    for (std::string line; std::getline(lines, line);) {
        std::smatch m;
        if (!std::regex_match(line, m, row)) continue;
        seen.push_back(m[1].str() + " " + m[2].str());
        const double t0 = std::stod(m[3]), t1 = std::stod(m[4]), t2 = std::stod(m[5]), ratio = std::stod(m[6]);
        REQUIRE(t0 > 0);
        // The last column is the others' arithmetic, to the rounding of the printed figures.
        CHECK(std::abs(ratio - (t2 - t1) / t0) <= 0.01 + 1e-6 * (2 + std::abs(ratio)) / t0);
    }
    // The suite's dimensions, 10 and 20, each optimiser at each.
    CHECK(seen == std::vector<std::string>{"lshade 10", "gwo 10", "lshade 20", "gwo 20"});
}

TEST_CASE("complexity refuses what it cannot time, exit 2", "[cli][complexity]") {
    TemporaryDirectory dir;
    auto refused = [&](const std::vector<std::string>& arguments, const std::string& message) {
        const auto run = run_mhbench(arguments, dir.path() / "log");
        CHECK(run.exit_code == 2);
        CHECK_THAT(run.output, Catch::Contains(message));
    };
    refused({"complexity", "lshade"}, "--problem: give --suite cec2017|cec2022 or a --problem to time");
    refused({"complexity", "lshade", "--suite", "cec2014"}, "--suite: expects cec2017 or cec2022 (got 'cec2014')");
    refused({"complexity", "nonesuch", "--suite", "cec2022"}, "nonesuch");
    refused({"complexity", "lshade", "--suite", "cec2022", "--dimension", "7"}, "--dimension");
    refused({"complexity", "lshade", "--problem", "cec2022_f1", "--dimension", "10"}, "--t0-iterations: give --suite or the iterations");
}

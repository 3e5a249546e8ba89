// `mhbench evaluate`: values of any registered problem at given points, and each bad input refused
// with a message naming the line, exit code 2.
#include <catch2/catch.hpp>

#include <sstream>
#include <string>

#include <fmt/format.h>

#include "framework/process.hpp"
#include "framework/registry.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::testing;

namespace {

std::vector<double> values_of(const std::string& output) {
    std::istringstream in(output);
    std::vector<double> out;
    for (std::string line; std::getline(in, line);)
        if (!line.empty() && line.rfind("note:", 0) != 0) out.push_back(std::stod(line));
    return out;
}

}  // namespace

TEST_CASE("evaluate prints 17 significant digits per point, in order, for CEC, BBOB and classic problems", "[cli][evaluate]") {
    TemporaryDirectory dir;
    // CEC 2022 F1 at D = 2: two rows of the organisers' reference file (the shift vector, f = F*, and
    // a uniform point), one separated by a space, one by a comma.
    const auto points = dir.write("points.txt",
                                  "-55.938326705218444 4.543065393596464\n"
                                  "22.53074289500961,64.29727411209231\n");
    const auto run = run_mhbench({"evaluate", "cec2022_f1", "--dimension", "2", "--points", points.string()}, dir.path() / "log");
    REQUIRE(run.exit_code == 0);
    const auto f = values_of(run.output);
    REQUIRE(f.size() == 2);
    CHECK(f[0] == Approx(300).epsilon(1e-12));
    CHECK(f[1] == Approx(307475.81247558631).epsilon(1e-12));
    const auto problem = make_problem("cec2022_f1", {{"dimension", std::int64_t{2}}});
    Matrix x(2, 2);
    x << -55.938326705218444, 22.53074289500961, 4.543065393596464, 64.29727411209231;
    Vector batch(2);
    problem->evaluate(x, batch);
    CHECK(run.output == fmt::format("{:.17g}\n{:.17g}\n", batch[0], batch[1]));

    // BBOB with an instance: f(x_opt) = f_opt, which the problem knows.
    const auto bbob = make_problem("bbob_f3", {{"dimension", std::int64_t{3}}, {"instance", std::int64_t{2}}});
    const auto& xopt = *bbob->truth().true_parameters;
    const auto at_opt = dir.write("opt.txt", fmt::format("{:.17g}\t{:.17g}\t{:.17g}\n", xopt[0], xopt[1], xopt[2]));
    const auto b = run_mhbench({"evaluate", "bbob_f3", "--dimension", "3", "--instance", "2", "--points", at_opt.string()},
                               dir.path() / "log2");
    REQUIRE(b.exit_code == 0);
    REQUIRE(values_of(b.output).size() == 1);
    CHECK(values_of(b.output)[0] == Approx(*bbob->truth().optimum_value).epsilon(1e-12));

    // A classic function of fixed dimension, from standard input.
    std::ofstream(dir.path() / "stdin.txt") << "-31.97833 -31.97833\n0 0\n";
    const auto s = run_program({MHBENCH_CLI, "evaluate", "F14", "--points", "-"}, dir.path() / "stdin.txt", dir.path() / "out3");
    REQUIRE(s.exit_code == 0);
    const auto v = values_of(read_file(dir.path() / "out3"));
    REQUIRE(v.size() == 2);
    CHECK(v[0] == Approx(0.998003838).epsilon(1e-6));  // Shekel's foxholes at its minimiser
    CHECK(v[1] > v[0]);
}

TEST_CASE("evaluate refuses each bad input with the line and exit code 2", "[cli][evaluate]") {
    TemporaryDirectory dir;
    auto refused = [&](const std::string& text, const std::vector<std::string>& options, const std::string& message) {
        const auto points = dir.write("p.txt", text);
        std::vector<std::string> args{"evaluate"};
        args.insert(args.end(), options.begin(), options.end());
        args.push_back("--points");
        args.push_back(points.string());
        const auto run = run_mhbench(args, dir.path() / "log");
        INFO(run.output);
        CHECK(run.exit_code == 2);
        CHECK_THAT(run.output, Catch::Contains(message));
        CHECK(run.output.rfind("error: ", 0) == 0);  // the message, and no value before it
    };
    const std::vector<std::string> cec{"cec2022_f1", "--dimension", "2"};
    refused("1 2\n1 2 3\n", cec, "p.txt:2: 3 number(s); cec2022_f1 with dimension 2 needs 2 per line");
    refused("1 2\n\n", cec, "p.txt:2: 0 number(s)");
    refused("1 2\n3 abc\n", cec, "p.txt:2: field 2: 'abc' is not a number");
    refused("1,,2\n", cec, "p.txt:1: field 2: empty (two separators in a row)");
    refused("1,2,\n", cec, "p.txt:1: field 3: empty (the line ends with a comma)");
    refused("1 nan\n", cec, "p.txt:1: field 2: 'nan' is not finite");
    refused("1 2\n", {"cec2017_f11", "--dimension", "20"}, "--dimension: cec2017_f11 is defined for D = 10, 30, 50, 100 only");
    refused("1 2\n", {"F14", "--dimension", "3"}, "--dimension: the problem F14 has a fixed dimension of 2 (got 3)");
    refused("1 2\n", {"F1", "--dimension", "2", "--instance", "3"}, "--instance: the problem F1 has no instances");
    refused("1 2\n", {"cec2099_f1"}, "unknown problem 'cec2099_f1'");
    refused("", cec, "p.txt: no points");
    const auto missing = run_mhbench({"evaluate", "F1", "--points", (dir.path() / "absent.txt").string()}, dir.path() / "log");
    CHECK(missing.exit_code == 2);
    CHECK_THAT(missing.output, Catch::Contains("absent.txt: cannot open the points file"));
}

TEST_CASE("evaluate evaluates points outside the box and says so once", "[cli][evaluate]") {
    TemporaryDirectory dir;
    const auto points = dir.write("p.csv", "0,0\n150,0\n0,-101\n1,1\n");
    const auto run = run_mhbench({"evaluate", "F1", "--dimension", "2", "--points", points.string()}, dir.path() / "log");
    REQUIRE(run.exit_code == 0);
    CHECK_THAT(run.output, Catch::Contains("note: " + points.string() + ": 2 point(s) outside the box of F1, the first on line 2"));
    CHECK(values_of(run.output) == std::vector<double>{0, 22500, 10201, 2});
}

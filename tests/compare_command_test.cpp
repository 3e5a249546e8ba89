// `mhbench compare`: an optimiser's runs against another program's, problem by problem, with the
// p-values checked against the exact rank-sum distribution and Holm's rule worked by hand.
#include <catch2/catch.hpp>

#include <fmt/format.h>

#include "framework/results_store.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::testing;

TEST_CASE("compare gives each problem's rank-sum p, Holm-adjusted over the problems, and refuses bad samples", "[cli][compare]") {
    TemporaryDirectory dir;
    const auto config = dir.write("e.toml", "trials = 6\nseed = 3\n[budget]\nevaluations = 200\n[[optimizer]]\nname = \"random_search\"\n"
                                            "[[problem]]\nname = \"cec2022_f1\"\ndimension = [2, 10]\n");
    REQUIRE(run_mhbench({"run", config.string(), "--out", (dir.path() / "out").string(), "--quiet", "--no-plots"}, dir.path() / "log").exit_code == 0);
    const auto records = read_results(dir.path() / "out" / "results.jsonl").records;
    REQUIRE(records.size() == 12);
    // Dimension 2: the other program's runs all far worse, so A12 = 1 (complete separation of 6 against 6: exact
    // two-sided p = 2 / C(12, 6) = 2/924). Dimension 10: the very same values (every pair tied: p = 1).
    std::string samples = "# problem value\n";
    for (const auto& r : records)
        samples += r.problem == "cec2022_f1(dimension=2)" ? fmt::format("{} {:.17g}\n", r.problem, r.best_fitness + 1e6)
                                                           : fmt::format("{}\t{:.17g}\n", r.problem, r.best_fitness);
    const auto file = dir.write("samples.txt", samples);
    const auto run = run_mhbench({"compare", (dir.path() / "out").string(), "--optimizer", "random_search", "--samples", file.string(),
                                  "--name", "theirs"},
                                 dir.path() / "log");
    REQUIRE(run.exit_code == 0);
    // Holm: 2/924 times 2, then max(that, 1 x 1).
    CHECK_THAT(run.output, Catch::Contains(fmt::format("| {:.3g} | {:.3g} | 1.00 |", 2.0 / 924, 4.0 / 924)));
    CHECK_THAT(run.output, Catch::Contains("| 1 | 1 | 0.50 |"));
    CHECK_THAT(run.output, Catch::Contains("1 of 2 problems differ at p < 0.01 after Holm's adjustment"));

    auto refused = [&](const std::string& text, const std::string& message, const std::string& optimizer = "random_search") {
        const auto bad = dir.write("bad.txt", text);
        const auto r = run_mhbench({"compare", (dir.path() / "out").string(), "--optimizer", optimizer, "--samples", bad.string()}, dir.path() / "log");
        CHECK(r.exit_code == 2);
        CHECK_THAT(r.output, Catch::Contains(message));
    };
    refused("cec2022_f1(dimension=2) 1\ncec2022_f1(dimension=3) 1\n", "bad.txt:2: problem: 'cec2022_f1(dimension=3)' is not a problem label");
    refused("cec2022_f1(dimension=2) one\n", "bad.txt:1: value: 'one' is not a finite number");
    refused("cec2022_f1(dimension=2)\n", "bad.txt:1: expects two fields");
    refused("# nothing\n", "no samples");
    refused("cec2022_f1(dimension=2) 1\n", "--optimizer: 'gwo' is not an optimizer label", "gwo");
}

// Plots: user text (labels, paths, model names) reaches gnuplot only as inert literals, so a config
// someone sends cannot run commands through the plots.
#include <catch2/catch.hpp>

#include <filesystem>

#include "framework/plots.hpp"
#include "framework/process.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
namespace fs = std::filesystem;

namespace {
// Every way a string has been known to run a command in gnuplot or in a shell.
std::vector<std::string> hostile_texts(const fs::path& marker) {
    const std::string m = marker.string();
    return {"GWO`touch " + m + "`", "res_$(touch " + m + ")", "a'b`touch " + m + "`'c", "x\nsystem('touch " + m + "')\n",
            "q\"`touch " + m + "`\"", "back\\slash'`touch " + m + "`", "@macro `touch " + m + "`"};
}
}  // namespace

TEST_CASE("gnuplot_quote: gnuplot prints the text back and runs nothing", "[plots]") {
    testing::TemporaryDirectory dir;
    const auto marker = dir.path() / "pwned";
    for (const auto& text : hostile_texts(marker)) {
        const auto script = dir.write("print.gp", "print " + gnuplot_quote(text) + "\n");
        const auto out = dir.path() / "out.txt";
        const auto run = run_program({"gnuplot"}, script, out);
        REQUIRE(run.exit_code == 0);
        std::string expected = text;
        for (char& c : expected)
            if (c == '\n') c = ' ';
        REQUIRE(testing::read_file(out) == expected + "\n");
        REQUIRE_FALSE(fs::exists(marker));
    }
}

TEST_CASE("render_gnuplot draws into a directory whose name is shell syntax, running nothing", "[plots]") {
    testing::TemporaryDirectory dir;
    const auto marker = dir.path() / "pwned";
    for (const auto& text : hostile_texts(marker)) {
        // A newline cannot be part of a file name the test can clean up portably; the rest can.
        if (text.find('\n') != std::string::npos) continue;
        const fs::path out_dir = dir.path() / text;
        fs::create_directories(out_dir);
        std::string error;
        const bool drawn = render_gnuplot(out_dir / "plot", "set title " + gnuplot_quote(text) + "\nplot x\n", 400, 300, error);
        INFO(error);
        REQUIRE(drawn);
        REQUIRE(fs::exists(out_dir / "plot.png"));
        REQUIRE(fs::exists(out_dir / "plot.svg"));
        REQUIRE_FALSE(fs::exists(marker));
    }
}

TEST_CASE("an experiment with hostile labels and output directory runs nothing through its plots", "[plots][cli]") {
    testing::TemporaryDirectory dir;
    const auto marker = dir.path() / "pwned";
    const std::string m = marker.string();
    // TOML basic strings: backslashes and quotes escaped, the backquotes and $(...) kept.
    const auto config = dir.write("hostile.toml", "name = \"hostile\"\ntrials = 2\nseed = 1\noutput = \"res_$(touch " + m +
                                                      ")\"\n[budget]\niterations = 5\n"
                                                      "[[optimizer]]\nname = \"random_search\"\nlabel = \"GWO`touch " + m +
                                                      "`\"\n[[problem]]\nname = \"F1\"\nlabel = \"F1'`touch " + m + "`'\"\n");
    auto run = testing::run_mhbench({"run", config.string(), "--quiet"}, dir.path() / "log1");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    REQUIRE_FALSE(fs::exists(marker));
    bool drew = false;
    for (const auto& entry : fs::recursive_directory_iterator(dir.path()))
        drew = drew || entry.path().filename().string().starts_with("convergence_");
    REQUIRE(drew);

    const auto out = dir.path() / ("out_$(touch " + m + ")`touch " + m + "`");
    run = testing::run_mhbench({"run", config.string(), "--quiet", "--out", out.string()}, dir.path() / "log2");
    REQUIRE(run.exit_code == 0);
    REQUIRE_FALSE(fs::exists(marker));
    REQUIRE(fs::exists(out / "table.md"));
}

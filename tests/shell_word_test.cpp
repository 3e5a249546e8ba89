// framework/shell_word.hpp against a shell itself: each word, pasted into a command line that sh
// runs, reaches the program as the one argument it was made from.
#include <catch2/catch.hpp>

#include <string>

#include "framework/shell_word.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

TEST_CASE("a shell word reaches the program as the text it was made from", "[cli]") {
    // Bare where no shell acts on any character: a model spec without held values, a plain path.
    CHECK(shell_word("base+deadtime") == "base+deadtime");
    CHECK(shell_word("data/run_1.csv") == "data/run_1.csv");
    testing::TemporaryDirectory dir;
    for (const std::string text : {"base+saturation(q_self=0,q_knee=0.5)", "my data.csv", "it's here.csv", "a;b", "$HOME", "*", ""}) {
        INFO(text);
        if (!text.empty()) CHECK(shell_word(text) != text);
        const auto run = testing::run_command({"sh", "-c", "printf '[%s]' " + shell_word(text)}, dir.path() / "out.log");
        REQUIRE(run.exit_code == 0);
        CHECK(run.output == "[" + text + "]");
    }
}

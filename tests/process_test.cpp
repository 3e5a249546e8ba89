// run_program: external programs start without a shell.
#include <catch2/catch.hpp>

#include <filesystem>

#include "framework/process.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;

TEST_CASE("run_program passes shell syntax to the program as plain text", "[process]") {
    testing::TemporaryDirectory dir;
    const auto marker = dir.path() / "pwned";
    const std::string hostile = "$(touch " + marker.string() + ") `touch " + marker.string() + "`; touch " + marker.string();
    const auto out = dir.path() / "out.txt";
    const auto run = run_program({"printf", "%s", hostile}, std::nullopt, out);
    REQUIRE(run.started);
    REQUIRE(run.exit_code == 0);
    REQUIRE(testing::read_file(out) == hostile);
    REQUIRE_FALSE(std::filesystem::exists(marker));
}

TEST_CASE("run_program feeds a file to standard input and reports the exit code", "[process]") {
    testing::TemporaryDirectory dir;
    const auto in = dir.write("in.txt", "three\nlines\nhere\n");
    const auto out = dir.path() / "out.txt";
    auto run = run_program({"wc", "-l"}, in, out);
    REQUIRE(run.exit_code == 0);
    REQUIRE(testing::read_file(out) == "3\n");
    run = run_program({"sh", "-c", "exit 7"}, std::nullopt, std::nullopt);
    REQUIRE(run.started);
    REQUIRE(run.exit_code == 7);
}

TEST_CASE("run_program says so when the program does not exist", "[process]") {
    const auto run = run_program({"mhbench-no-such-program"}, std::nullopt, std::nullopt);
    REQUIRE_FALSE(run.started);
    REQUIRE_THAT(run.error, Catch::Contains("mhbench-no-such-program"));
}

TEST_CASE("run_program keeps standard error apart when given a file for it", "[process]") {
    testing::TemporaryDirectory dir;
    const auto out = dir.path() / "out.txt", err = dir.path() / "err.txt";
    auto run = run_program({"sh", "-c", "echo result; echo chatter >&2"}, std::nullopt, out, err);
    REQUIRE(run.exit_code == 0);
    REQUIRE(testing::read_file(out) == "result\n");
    REQUIRE(testing::read_file(err) == "chatter\n");
    // Without one, both go to the output, as before.
    run = run_program({"sh", "-c", "echo result; echo chatter >&2"}, std::nullopt, out);
    REQUIRE(testing::read_file(out) == "result\nchatter\n");
}

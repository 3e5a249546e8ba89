// Plugins built out of tree, as a user builds them: `cmake --install` of this build into a fresh
// prefix, a CMake project that finds the installed package and links mhbench::plugin, and the
// installed program loading the libraries with --plugin or an experiment's `plugins = [...]`.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "framework/plugin_loader.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using mhb::testing::TemporaryDirectory;
namespace fs = std::filesystem;

namespace {

using Outcome = testing::CliRun;
const auto run = testing::run_command;

// Installs this build into `prefix` and builds the CMake project in `source` against it, in `build`.
void build_against_installed(const fs::path& prefix, const fs::path& source, const fs::path& build, const fs::path& logs) {
    const auto install = run({MHBENCH_CMAKE, "--install", MHBENCH_BUILD_DIR, "--prefix", prefix.string()}, logs / "install.log");
    INFO(install.output);
    REQUIRE(install.exit_code == 0);
    // The program's own compile flags: a plugin of a sanitizer build must be instrumented too (an
    // uninstrumented destructor freeing what the instrumented program allocated is reported as a bad free).
    const auto configure = run({MHBENCH_CMAKE, "-S", source.string(), "-B", build.string(), "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                                "-DCMAKE_PREFIX_PATH=" + prefix.string(), "-DCMAKE_CXX_COMPILER=" MHBENCH_CXX_COMPILER,
                                "-DCMAKE_CXX_FLAGS=" MHBENCH_CXX_FLAGS, "-DCMAKE_MODULE_LINKER_FLAGS=" MHBENCH_SHARED_LINKER_FLAGS,
                                "-DCMAKE_SHARED_LINKER_FLAGS=" MHBENCH_SHARED_LINKER_FLAGS},
                               logs / "configure.log");
    INFO(configure.output);
    REQUIRE(configure.exit_code == 0);
    const auto compile = run({MHBENCH_CMAKE, "--build", build.string()}, logs / "build.log");
    INFO(compile.output);
    REQUIRE(compile.exit_code == 0);
}

}  // namespace

TEST_CASE("the docs' example plugins build against the installed package and load into the installed program",
          "[plugin][install]") {
    TemporaryDirectory dir;
    const fs::path prefix = dir.path() / "prefix", build = dir.path() / "examples";
    build_against_installed(prefix, fs::path(MHBENCH_SOURCE_DIR) / "docs" / "examples", build, dir.path());

    // The interfaces a plugin needs are installed, the runner's insides are not.
    CHECK(fs::exists(prefix / "include/mhbench/framework/registry.hpp"));
    CHECK(fs::exists(prefix / "include/mhbench/problems/pmsm/effects/effect.hpp"));
    // Headers that moved into problems/pmsm/'s rooms still answer at their old paths.
    for (const char* old : {"machine.hpp", "measurement.hpp", "column_map.hpp"}) {
        std::ifstream forwarding(prefix / "include/mhbench/problems/pmsm" / old);
        std::stringstream text;
        text << forwarding.rdbuf();
        INFO(old);
        CHECK(text.str().find("#include \"problems/pmsm/") != std::string::npos);
    }
    CHECK_FALSE(fs::exists(prefix / "include/mhbench/framework/experiment_runner.hpp"));
    CHECK_FALSE(fs::exists(prefix / "include/mhbench/framework/results_store.hpp"));

    const std::string mhbench = (prefix / "bin" / "mhbench").string();
    const std::string optimizer = (build / "libgaussian_search.so").string(), effect = (build / "libslot_harmonic.so").string();
    const auto bare = run({mhbench, "list", "--brief"}, dir.path() / "bare.log");
    REQUIRE(bare.exit_code == 0);
    CHECK(bare.output.find("gaussian_search") == std::string::npos);
    CHECK(bare.output.find("slot_harmonic") == std::string::npos);

    const auto listed = run({mhbench, "--plugin", optimizer, "--plugin=" + effect, "list", "--brief"}, dir.path() / "list.log");
    INFO(listed.output);
    REQUIRE(listed.exit_code == 0);
    CHECK(listed.output.find("gaussian_search") != std::string::npos);
    CHECK(listed.output.find("slot_harmonic") != std::string::npos);

    // The effect's model code runs inside the program's PMSM fit; the paper's data has no slot
    // harmonic, so its amplitudes are small.
    const auto fit = run({mhbench, "--plugin", effect, "fit", "--data", MHBENCH_SOURCE_DIR "/experiments/pmsm/paper_data.csv",
                          "--model", "base+slot_harmonic"},
                         dir.path() / "fit.log");
    INFO(fit.output);
    CHECK(fit.exit_code == 0);
    CHECK(fit.output.find("h11") != std::string::npos);

    // An experiment names its plugin, relative to the config file; its trials run with it.
    fs::copy_file(optimizer, dir.path() / "libgaussian_search.so");
    const auto config = dir.write("plugin.toml", R"(name = "plugin"
trials = 3
seed = 5
output = "out"
plugins = ["libgaussian_search.so"]

[budget]
evaluations = 2000

[[optimizer]]
name = "example_gaussian_search"

[[problem]]
name = "F1"
dimension = 5
)");
    const auto ran = run({mhbench, "run", config.string(), "--quiet", "--no-plots"}, dir.path() / "run.log");
    INFO(ran.output);
    REQUIRE(ran.exit_code == 0);
    const std::string results = testing::read_file(dir.path() / "out" / "results.jsonl");
    CHECK(std::count(results.begin(), results.end(), '\n') == 3);
    CHECK(results.find("\"example_gaussian_search\"") != std::string::npos);
    // The tables come from the directory alone: no plugin needed to remake them.
    const auto table = run({mhbench, "table", (dir.path() / "out").string(), "--no-plots"}, dir.path() / "table.log");
    INFO(table.output);
    CHECK(table.exit_code == 0);
    CHECK(table.output.find("example_gaussian_search") != std::string::npos);
    // The same library named on the command line and in the config is loaded once.
    const std::string copy = (dir.path() / "libgaussian_search.so").string();
    const auto twice = run({mhbench, "--plugin", copy, "run", config.string(), "--quiet", "--no-plots"}, dir.path() / "twice.log");
    INFO(twice.output);
    CHECK(twice.exit_code == 0);
    // Two files registering one name: the second is refused, naming both.
    const auto two = run({mhbench, "--plugin", optimizer, "run", config.string(), "--quiet"}, dir.path() / "two.log");
    INFO(two.output);
    CHECK(two.exit_code == 2);
    CHECK(two.output.find(config.string() + ":5: plugins[0]: the optimizer 'example_gaussian_search' of " + copy +
                          " clashes with the optimizer 'example_gaussian_search' of " + optimizer) != std::string::npos);
}

TEST_CASE("a plugin library that does not fit is refused, naming the file and the reason, with exit code 2",
          "[plugin][install]") {
    TemporaryDirectory dir;
    const fs::path prefix = dir.path() / "prefix", build = dir.path() / "fixtures";
    build_against_installed(prefix, fs::path(MHBENCH_SOURCE_DIR) / "tests" / "plugin_fixtures", build, dir.path());
    const std::string mhbench = (prefix / "bin" / "mhbench").string();
    const auto library = [&](const std::string& name) { return (build / ("lib" + name + ".so")).string(); };
    const auto refused = [&](const std::string& path, const std::string& log) {
        return run({mhbench, "--plugin", path, "list", "--brief"}, dir.path() / log);
    };

    const auto clash = refused(library("clashing_optimizer"), "clash.log");
    INFO(clash.output);
    CHECK(clash.exit_code == 2);
    CHECK(clash.output.find("error: command line: --plugin: the optimizer 'gwo' of " + library("clashing_optimizer") +
                            " clashes with the built-in optimizer 'gwo'") != std::string::npos);

    const auto stale = refused(library("stale_interface"), "stale.log");
    INFO(stale.output);
    CHECK(stale.exit_code == 2);
    CHECK(stale.output.find(library("stale_interface") + ": built against mhbench plugin interface version 0, but this mhbench has "
                            "interface version " + std::to_string(plugin_interface_version())) != std::string::npos);
    CHECK(stale.output.find("stale_optimizer") == std::string::npos);

    const auto undefined = refused(library("undefined_symbol"), "undefined.log");
    INFO(undefined.output);
    CHECK(undefined.exit_code == 2);
    CHECK(undefined.output.find(library("undefined_symbol") + ": cannot load:") != std::string::npos);
    CHECK(undefined.output.find("mhbench_fixture_function_nobody_defines") != std::string::npos);

    const auto foreign = refused(library("not_a_plugin"), "foreign.log");
    INFO(foreign.output);
    CHECK(foreign.exit_code == 2);
    CHECK(foreign.output.find(library("not_a_plugin") + ": not an mhbench plugin") != std::string::npos);

    const auto text = refused(dir.write("notes.so", "not a library\n").string(), "text.log");
    INFO(text.output);
    CHECK(text.exit_code == 2);
    CHECK(text.output.find("notes.so: not a shared library") != std::string::npos);

    const auto missing = refused((dir.path() / "libnowhere.so").string(), "missing.log");
    CHECK(missing.exit_code == 2);
    CHECK(missing.output.find("libnowhere.so: no such file") != std::string::npos);

    // In a config, the refusal names the file, line and list entry.
    const auto config = dir.write("stale.toml", "name = \"stale\"\ntrials = 1\nseed = 1\n\nplugins = [\n  \"" + library("stale_interface") +
                                                    "\",\n]\n\n[budget]\nevaluations = 100\n\n[[optimizer]]\nname = \"stale_optimizer\"\n\n"
                                                    "[[problem]]\nname = \"F1\"\ndimension = 2\n");
    const auto from_config = run({mhbench, "run", config.string()}, dir.path() / "config.log");
    INFO(from_config.output);
    CHECK(from_config.exit_code == 2);
    CHECK(from_config.output.find(config.string() + ":6: plugins[0]: " + library("stale_interface") + ": built against") !=
          std::string::npos);

    // A plugin may bring its own command.
    const auto hello = run({mhbench, "--plugin", library("hello_command"), "hello", "--name", "plugin"}, dir.path() / "hello.log");
    INFO(hello.output);
    CHECK(hello.exit_code == 0);
    CHECK(hello.output == "hello, plugin\n");
}

// The core (framework/) knows no optimiser and no problem: they are plugins that register themselves.
// The build checks the link (the core library links with --no-undefined); this checks the sources,
// so that a header-only dependency is caught too.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

namespace fs = std::filesystem;

TEST_CASE("no source of the core includes an optimizer or a problem", "[architecture]") {
    const fs::path framework = fs::path(MHBENCH_SOURCE_DIR) / "framework";
    const std::regex plugin_include(R"(^\s*#\s*include\s*["<](optimizers|problems)/)");
    std::size_t sources = 0;
    for (const auto& entry : fs::recursive_directory_iterator(framework)) {
        const auto ext = entry.path().extension();
        if (ext != ".cpp" && ext != ".hpp") continue;
        ++sources;
        std::ifstream in(entry.path());
        std::string line;
        for (long n = 1; std::getline(in, line); ++n) {
            INFO(entry.path().string() << ":" << n << ": " << line);
            CHECK_FALSE(std::regex_search(line, plugin_include));
        }
    }
    REQUIRE(sources > 20);
}

// The plugin interface version follows the installed headers: the digest of their code (comments and
// spacing left out) is recorded here for each version, and a change of the code without a new version
// fails, before a plugin built against the old headers could be loaded by a program that no longer
// matches it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "framework/plugin_interface.hpp"
#include "tests/plugin_interface_digest.hpp"

using mhb::testing::header_code;
using mhb::testing::interface_digest;

namespace {

// Each version's digest, one line a version, added when the version is raised (version 2's
// headers are those of commit 24a210f, the PMSM ones at their paths before problems/pmsm/ had rooms).
const std::vector<std::pair<int, std::uint64_t>> recorded_digests{
    {2, 0xcad1e07a0558ab18ull},
    {3, 0x1ec5b7b2a00e3a26ull},
    {4, 0x8c1be0ce9150a544ull},
    {5, 0x81fe429d0920edfdull},
    {6, 0x83d6085f06c459f3ull},
    {7, 0x6696ff8b7b755384ull},
    {8, 0x3be526f34edc3e9aull},
    {9, 0x58a75625599557acull},
    {10, 0xd0b677bea2847a88ull},
    {11, 0x8d16b1ce0806e448ull},
    {12, 0x082311889c20bd69ull},
    {13, 0x28d43f16582edc9dull},
    {14, 0xf5c7ae640ec00f0dull},
    {15, 0x4ba141b3e6a37f3dull},
    {16, 0x89f38010bcf02cdfull},
};

std::vector<std::string> installed_headers() {
    std::vector<std::string> out;
    std::stringstream list(MHBENCH_PUBLIC_HEADERS);
    for (std::string header; std::getline(list, header, ',');)
        if (!header.empty()) out.push_back(header);
    return out;
}

}  // namespace

TEST_CASE("header code: comments and spacing do not count, code and string contents do", "[plugin][interface]") {
    CHECK(header_code("int f(int a); // the count\n") == header_code("int  f(int a);\n\n/* none */"));
    CHECK(header_code("/* a\n b */ double x;") == "double x;");
    CHECK(header_code("struct S {\n    int a;\n};") == "struct S { int a; };");
    // A comment marker inside a string or a character is code.
    CHECK(header_code(R"(const char* url = "https://example.org"; // comment)") == R"(const char* url = "https://example.org";)");
    CHECK(header_code(R"(char q = '"'; int b; // x)") == R"(char q = '"'; int b;)");
    CHECK(header_code(R"(const char* s = "a \" // b"; int c;)") == R"(const char* s = "a \" // b"; int c;)");
    CHECK(header_code("int a;") != header_code("int b;"));
    CHECK(header_code("virtual void f() const;") != header_code("virtual void f();"));
}

TEST_CASE("the digest changes with any file's code, its name or the order of files", "[plugin][interface]") {
    const std::vector<std::pair<std::string, std::string>> files{{"a.hpp", "int a;"}, {"b.hpp", "int b;"}};
    const auto digest = interface_digest(files);
    CHECK(interface_digest({{"a.hpp", "int a; // comment"}, {"b.hpp", "int  b;"}}) == digest);
    CHECK(interface_digest({{"a.hpp", "int a;"}, {"b.hpp", "long b;"}}) != digest);
    CHECK(interface_digest({{"c.hpp", "int a;"}, {"b.hpp", "int b;"}}) != digest);
    CHECK(interface_digest({{"b.hpp", "int b;"}, {"a.hpp", "int a;"}}) != digest);
    // Moving code from one file's end to the next file's start is a change too.
    CHECK(interface_digest({{"a.hpp", "int a; int b;"}, {"b.hpp", ""}}) != interface_digest({{"a.hpp", "int a;"}, {"b.hpp", "int b;"}}));
}

TEST_CASE("the installed headers have the digest recorded for this plugin interface version", "[plugin][interface]") {
    std::vector<std::pair<std::string, std::string>> files;
    for (const auto& header : installed_headers()) {
        // The file that records the digest cannot be part of it.
        if (header == "framework/plugin_interface.hpp") continue;
        std::ifstream in(std::filesystem::path(MHBENCH_SOURCE_DIR) / header);
        REQUIRE(in);
        std::stringstream text;
        text << in.rdbuf();
        files.emplace_back(header, text.str());
    }
    std::sort(files.begin(), files.end());
    REQUIRE(files.size() >= 10);
    const std::uint64_t digest = interface_digest(files);
    // One digest a version, versions in order, the last one this program's.
    for (std::size_t k = 1; k < recorded_digests.size(); ++k) {
        CHECK(recorded_digests[k].first == recorded_digests[k - 1].first + 1);
        CHECK(recorded_digests[k].second != recorded_digests[k - 1].second);
    }
    REQUIRE(recorded_digests.back().first == MHBENCH_PLUGIN_INTERFACE_VERSION);
    INFO(fmt::format("The installed headers' code has digest 0x{:016x}, but version {} was recorded with 0x{:016x}: the plugin "
                     "interface changed. Raise MHBENCH_PLUGIN_INTERFACE_VERSION in framework/plugin_interface.hpp (saying what "
                     "changed) and add {{{}, 0x{:016x}ull}} to recorded_digests in this file.",
                     digest, MHBENCH_PLUGIN_INTERFACE_VERSION, recorded_digests.back().second,
                     MHBENCH_PLUGIN_INTERFACE_VERSION + 1, digest));
    CHECK(digest == recorded_digests.back().second);
}

#pragma once
// The digest of the plugin interface's code (tests/plugin_interface_test.cpp): comments and runs of
// spacing are not code, so rewording a comment or reformatting needs no new interface version.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mhb::testing {

// `text` without comments, each run of spacing one space, none at either end. String and character
// literals are kept as written (a "//" inside one is code).
inline std::string header_code(std::string_view text) {
    std::string out;
    bool pending_space = false;
    auto put = [&](char c) {
        if (pending_space && !out.empty()) out += ' ';
        pending_space = false;
        out += c;
    };
    for (std::size_t k = 0; k < text.size(); ++k) {
        const char c = text[k];
        if (c == '/' && k + 1 < text.size() && text[k + 1] == '/') {
            while (k < text.size() && text[k] != '\n') ++k;
            pending_space = true;
        } else if (c == '/' && k + 1 < text.size() && text[k + 1] == '*') {
            const auto end = text.find("*/", k + 2);
            k = end == std::string_view::npos ? text.size() : end + 1;
            pending_space = true;
        } else if (c == '"' || c == '\'') {
            put(c);
            for (++k; k < text.size() && text[k] != c; ++k) {
                out += text[k];
                if (text[k] == '\\' && k + 1 < text.size()) out += text[++k];
            }
            if (k < text.size()) out += c;
        } else if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v') {
            pending_space = true;
        } else {
            put(c);
        }
    }
    return out;
}

// FNV-1a over each file's name and code, in the order given, with a separator that no code holds.
inline std::uint64_t interface_digest(const std::vector<std::pair<std::string, std::string>>& files) {
    std::uint64_t h = 14695981039346656037ull;
    auto mix = [&](std::string_view s) {
        for (unsigned char c : s) {
            h ^= c;
            h *= 1099511628211ull;
        }
        h ^= 0xffu;  // not a byte of UTF-8 text
        h *= 1099511628211ull;
    };
    for (const auto& [name, text] : files) {
        mix(name);
        mix(header_code(text));
    }
    return h;
}

}  // namespace mhb::testing

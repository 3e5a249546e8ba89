#include "framework/closest_name.hpp"

#include <algorithm>
#include <cctype>

namespace mhb {
namespace {

std::size_t edit_distance(const std::string& a, const std::string& b) {
    auto same = [](char x, char y) {
        return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
    };
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (same(a[i - 1], b[j - 1]) ? 0 : 1)});
            diagonal = above;
        }
    }
    return row[b.size()];
}

}  // namespace

std::string closest_name(const std::string& typed, const std::vector<std::string>& known) {
    std::string best;
    std::size_t best_distance = std::max<std::size_t>(2, typed.size() / 3) + 1;
    for (const auto& name : known) {
        const std::size_t d = edit_distance(typed, name);
        if (d < best_distance) {
            best = name;
            best_distance = d;
        }
    }
    return best;
}

std::string unknown_name_message(const std::string& kind, const std::string& typed, const std::vector<std::string>& known) {
    std::string out = "unknown " + kind + " '" + typed + "'";
    if (const auto near = closest_name(typed, known); !near.empty()) out += "; did you mean '" + near + "'?";
    out += " Registered " + kind + "s:";
    for (const auto& name : known) out += "\n  " + name;
    return out;
}

}  // namespace mhb

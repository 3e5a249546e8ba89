#pragma once
// Range checks for numeric command-line options, applied to the text as typed: CLI11 turns a number
// beyond the type's range into the type's limit and a negative into a default before its own Range
// validator sees it, so `--evaluations 99999999999999999999` would otherwise run forever.
#include <charconv>
#include <cmath>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

namespace mhb::cli {

// A whole number in [lo, hi]. CLI11 prefixes the option's name to the message.
template <class Integer>
CLI::Validator whole_number_in(Integer lo, Integer hi) {
    return CLI::Validator(
        [lo, hi](std::string& text) -> std::string {
            Integer value{};
            const char* end = text.data() + text.size();
            const auto [stop, ec] = std::from_chars(text.data(), end, value);
            if (!text.empty() && ec == std::errc() && stop == end && value >= lo && value <= hi) return {};
            return fmt::format("expects a whole number in [{}, {}] (got '{}')", lo, hi, text);
        },
        fmt::format("INT in [{}, {}]", lo, hi));
}

// A finite number in [lo, hi].
inline CLI::Validator number_in(double lo, double hi) {
    return CLI::Validator(
        [lo, hi](std::string& text) -> std::string {
            double value = 0.0;
            const char* end = text.data() + text.size();
            const auto [stop, ec] = std::from_chars(text.data(), end, value);
            if (!text.empty() && ec == std::errc() && stop == end && std::isfinite(value) && value >= lo && value <= hi)
                return {};
            return fmt::format("expects a number in [{}, {}] (got '{}')", lo, hi, text);
        },
        fmt::format("NUMBER in [{}, {}]", lo, hi));
}

}  // namespace mhb::cli

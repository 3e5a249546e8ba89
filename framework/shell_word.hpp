#pragma once
// Command lines printed for the user to paste into a shell (the next command a diagnosis suggests):
// each argument written as one shell word.
#include <string>

namespace mhb {

// `text` as one shell word: bare when it holds only characters no shell acts on, else single-quoted
// (a model spec with held values, base+delay(tau=0.00015), has parentheses).
inline std::string shell_word(const std::string& text) {
    const bool bare = !text.empty() && text.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                                              "0123456789_./=,:+-") == std::string::npos;
    if (bare) return text;
    std::string out = "'";
    for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

}  // namespace mhb

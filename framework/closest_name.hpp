#pragma once
// Messages for a name that is not known (an optimizer, a problem, a command): the closest known name
// as a suggestion, and the known names one per line, so a typo is fixed by reading one line.
#include <string>
#include <vector>

namespace mhb {

// The known name nearest to `typed` (case-insensitive edit distance), or "" when none is near enough
// to be a likely typo (more than a third of the letters, and at least 2, differ).
std::string closest_name(const std::string& typed, const std::vector<std::string>& known);

// "unknown <kind> '<typed>'; did you mean '<closest>'? <kind>s:\n  a\n  b ..." (no suggestion when
// nothing is near).
std::string unknown_name_message(const std::string& kind, const std::string& typed, const std::vector<std::string>& known);

}  // namespace mhb

#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

namespace mhb::pmsm {

// The largest input file read whole: room for a measurement of max_measurement_rows rows at up to
// 256 bytes each. Reading stops there, so an endless input (/dev/zero) is refused, not exhausted.
inline constexpr std::uintmax_t max_text_file_bytes = 1'280'000'000;

// The whole file as bytes. mhb::InputError naming the path when it is a directory, cannot be opened
// (with the system's reason), or is larger than `max_bytes` (the limit in the message).
std::string read_text_file(const std::filesystem::path& path, const std::string& what,
                           std::uintmax_t max_bytes = max_text_file_bytes);

}  // namespace mhb::pmsm

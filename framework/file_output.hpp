#pragma once
// Writing the files a user keeps (experiment.json, tables, JSON reports) so that neither a kill nor a
// full disk leaves a half-written file in place of a good one.
#include <filesystem>
#include <string_view>

namespace mhb {

// Writes `text` to a temporary file beside `path`, then renames it over `path`: a reader (or a run
// killed at any moment) sees the old file or the new one, never a truncated one. Throws InputError
// naming `path` and the system's reason when it cannot be written (no directory, no permission, disk
// full); `path` is then unchanged.
void replace_file(const std::filesystem::path& path, std::string_view text);

}  // namespace mhb

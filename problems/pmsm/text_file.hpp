#pragma once
#include <filesystem>
#include <string>

namespace mhb::pmsm {

// The whole file as bytes; mhb::InputError "cannot open the <what>" when it cannot be read.
std::string read_text_file(const std::filesystem::path& path, const std::string& what);

}  // namespace mhb::pmsm

#include "problems/pmsm/text_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>

#include <fmt/format.h>

#include "framework/input_error.hpp"

namespace mhb::pmsm {

std::string read_text_file(const std::filesystem::path& path, const std::string& what, std::uintmax_t max_bytes) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw InputError(path.string(), 0, "", "is a directory; expected the " + what + " file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string(), 0, "", "cannot open the " + what + ": " + std::strerror(errno));
    std::string text;
    char buffer[1 << 16];
    while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
        text.append(buffer, static_cast<std::size_t>(in.gcount()));
        if (text.size() > max_bytes)
            throw InputError(path.string(), 0, "",
                             fmt::format("the {} is larger than the limit of {} bytes", what, max_bytes));
    }
    if (in.bad()) throw InputError(path.string(), 0, "", "reading the " + what + " failed: " + std::strerror(errno));
    return text;
}

}  // namespace mhb::pmsm

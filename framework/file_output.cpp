#include "framework/file_output.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include <unistd.h>

#include "framework/input_error.hpp"

namespace mhb {

namespace fs = std::filesystem;

void replace_file(const fs::path& path, std::string_view text) {
    // The pid keeps two processes writing the same directory from sharing a temporary file.
    fs::path temporary = path;
    temporary += ".tmp-" + std::to_string(::getpid());
    auto refuse = [&](const std::string& reason) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        throw InputError(path.string(), 0, "", "cannot write the file: " + reason);
    };
    std::FILE* out = std::fopen(temporary.c_str(), "wb");
    if (!out) refuse(std::strerror(errno));
    const bool written = std::fwrite(text.data(), 1, text.size(), out) == text.size() && std::fflush(out) == 0;
    const int write_errno = errno;
    if (std::fclose(out) != 0 || !written) refuse(std::strerror(written ? errno : write_errno));
    std::error_code ec;
    fs::rename(temporary, path, ec);
    if (ec) refuse(ec.message());
}

}  // namespace mhb

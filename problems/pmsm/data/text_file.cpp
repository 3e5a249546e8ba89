#include "problems/pmsm/data/text_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fmt/format.h>

#include "framework/input_error.hpp"

namespace mhb::pmsm {

FileBlocks::FileBlocks(const std::filesystem::path& path, const std::string& what, std::size_t block_bytes,
                       std::uintmax_t max_bytes)
    : path_(path), what_(what), max_bytes_(max_bytes), buffer_size_(std::max<std::size_t>(block_bytes, 1)) {
    buffer_ = std::make_unique_for_overwrite<char[]>(buffer_size_);
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw InputError(path.string(), 0, "", "is a directory; expected the " + what + " file");
    in_.open(path, std::ios::binary);
    if (!in_) throw InputError(path.string(), 0, "", "cannot open the " + what + ": " + std::strerror(errno));
}

std::string_view FileBlocks::next() {
    in_.read(buffer_.get(), static_cast<std::streamsize>(buffer_size_));
    const auto got = static_cast<std::size_t>(in_.gcount());
    if (got == 0) {
        if (in_.bad()) throw InputError(path_.string(), 0, "", "reading the " + what_ + " failed: " + std::strerror(errno));
        return {};
    }
    read_ += got;
    if (read_ > max_bytes_)
        throw InputError(path_.string(), 0, "", fmt::format("the {} is larger than the limit of {} bytes", what_, max_bytes_));
    return {buffer_.get(), got};
}

void FileBlocks::rewind() {
    in_.clear();
    in_.seekg(0);
    if (!in_)
        throw InputError(path_.string(), 0, "",
                         "cannot read the " + what_ + " a second time (a pipe?); mhbench reads it twice, so it must be a regular file");
    read_ = 0;
}

void require_regular_file(const std::filesystem::path& path, const std::string& what) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (status.type() == fs::file_type::not_found)
        throw InputError(path.string(), 0, "", "cannot open the " + what + ": No such file or directory");
    if (ec) throw InputError(path.string(), 0, "", "cannot open the " + what + ": " + ec.message());
    const char* kind = nullptr;
    switch (status.type()) {
        case fs::file_type::regular: return;
        case fs::file_type::directory: throw InputError(path.string(), 0, "", "is a directory; expected the " + what + " file");
        case fs::file_type::fifo: kind = "a FIFO (named pipe)"; break;
        case fs::file_type::socket: kind = "a socket"; break;
        case fs::file_type::character: kind = "a character device"; break;
        case fs::file_type::block: kind = "a block device"; break;
        default: kind = "of a kind that is neither a regular file nor a directory"; break;
    }
    throw InputError(path.string(), 0, "",
                     fmt::format("is {}; the {} must be a regular file (save the data to a file and give that)", kind, what));
}

std::string read_text_file(const std::filesystem::path& path, const std::string& what, std::uintmax_t max_bytes) {
    FileBlocks file(path, what, 1 << 16, max_bytes);
    std::string text;
    for (auto block = file.next(); !block.empty(); block = file.next()) text.append(block);
    return text;
}

}  // namespace mhb::pmsm

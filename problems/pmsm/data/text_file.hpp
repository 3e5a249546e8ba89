#pragma once
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <string_view>

namespace mhb::pmsm {

// The largest input file read: room for a measurement of max_measurement_rows rows at up to 256
// bytes each. Reading stops there, so an endless input (/dev/zero) is refused, not exhausted.
inline constexpr std::uintmax_t max_text_file_bytes = 1'280'000'000;

// A file read one block at a time, so that reading it costs a block of memory whatever its size.
// mhb::InputError naming the path when it is a directory, cannot be opened (with the system's
// reason), is larger than `max_bytes` (the limit in the message), or a read fails.
class FileBlocks {
public:
    FileBlocks(const std::filesystem::path& path, const std::string& what, std::size_t block_bytes,
               std::uintmax_t max_bytes = max_text_file_bytes);
    // The next block_bytes bytes (fewer at the end), empty after the last; valid until the next call.
    std::string_view next();
    // Back to the first byte, for a second reading; refused where the file cannot seek (a pipe).
    void rewind();

private:
    std::filesystem::path path_;
    std::string what_;
    std::uintmax_t max_bytes_;
    std::uintmax_t read_ = 0;
    std::ifstream in_;
    // Not zeroed: a block of 4 MiB cleared for a file of 100 kB would cost more than reading it (the
    // kernel faults in every page the clearing touches); only the pages a read fills are touched.
    std::unique_ptr<char[]> buffer_;
    std::size_t buffer_size_;
};

// mhb::InputError naming the path unless it is a regular file (after symbolic links), before anything
// opens it: opening a FIFO waits for a writer that may never come, a device may never end, and a
// binary reader given either would hang or read garbage. The reason names what the path is instead.
void require_regular_file(const std::filesystem::path& path, const std::string& what);

// The whole file as bytes, with FileBlocks' refusals.
std::string read_text_file(const std::filesystem::path& path, const std::string& what,
                           std::uintmax_t max_bytes = max_text_file_bytes);

}  // namespace mhb::pmsm

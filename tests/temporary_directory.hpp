#pragma once
// A fresh directory under the system temp dir, removed when the test ends.
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

namespace mhb::testing {

class TemporaryDirectory {
public:
    TemporaryDirectory() {
        std::random_device rd;
        path_ = std::filesystem::temp_directory_path() / ("mhbench-test-" + std::to_string(rd()) + std::to_string(rd()));
        std::filesystem::create_directories(path_);
    }
    ~TemporaryDirectory() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path write(const std::string& name, const std::string& text) const {
        const auto p = path_ / name;
        std::ofstream(p) << text;
        return p;
    }

private:
    std::filesystem::path path_;
};

inline std::string read_file(const std::filesystem::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

}  // namespace mhb::testing

#include "problems/pmsm/text_file.hpp"

#include <fstream>
#include <sstream>

#include "framework/input_error.hpp"

namespace mhb::pmsm {

std::string read_text_file(const std::filesystem::path& path, const std::string& what) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path.string(), 0, "", "cannot open the " + what);
    std::ostringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
}

}  // namespace mhb::pmsm

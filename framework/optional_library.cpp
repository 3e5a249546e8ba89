#include "framework/optional_library.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>

#include <fmt/format.h>

namespace mhb {

std::string optional_library_path(const std::string& name) {
    // The core library's own file, found from the address of this function: the optional libraries
    // are built and installed beside it, whichever program (mhbench, the tests, the Python module)
    // loaded it.
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&optional_library_path), &info) == 0 || !info.dli_fname)
        throw std::runtime_error(fmt::format("cannot find the directory of mhbench's core library, beside which "
                                             "libmhbench_{}.so is installed",
                                             name));
    const auto directory = std::filesystem::path(info.dli_fname).parent_path().lexically_normal();  // bin/../lib: lib
    return (directory / fmt::format("libmhbench_{}.so", name)).string();
}

void* optional_library_symbol(const std::string& name, const char* symbol) {
    static std::mutex mutex;
    static std::map<std::string, void*> handles;
    std::lock_guard lock(mutex);
    void*& handle = handles[name];
    if (!handle) {
        const std::string file = optional_library_path(name);
        // RTLD_LOCAL: what it brings stays out of the plugins' symbol lookups. (Debian's Open MPI 4.1
        // loads its components beside a libmpi loaded so: tests/mpi_run_test.cpp runs under mpirun.)
        handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!handle) {
            const char* reason = dlerror();
            // dlerror's reason names the file.
            throw std::runtime_error(fmt::format("cannot load mhbench's libmhbench_{}.so: {} (an incomplete installation? "
                                                 "`cmake --install` puts it beside libmhbench.so)",
                                                 name, reason ? reason : file + ": unknown reason"));
        }
    }
    dlerror();
    void* address = dlsym(handle, symbol);
    if (!address) {
        const char* reason = dlerror();
        throw std::runtime_error(fmt::format("{}: has no entry point {}: {} (a library of another mhbench version?)",
                                             optional_library_path(name), symbol, reason ? reason : "unknown reason"));
    }
    return address;
}

}  // namespace mhb

#pragma once
// Plugins loaded at run time: a shared library built against the installed package (find_package(mhbench),
// target mhbench::plugin) whose static registrations add optimisers, problems, effects or commands.
// `mhbench --plugin FILE` and an experiment's `plugins = [...]` both come here.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace mhb {

// Why a library was refused; the caller adds where its path came from (command line, config line).
class PluginLoadError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// The interface version this program was built with (framework/plugin_interface.hpp).
int plugin_interface_version();

// Loads `library` once (a second call with the same file does nothing). Before any of its code runs,
// its interface version is read from the file and must equal this program's; after loading, a name
// it registers that is taken already refuses it, naming both. The library stays loaded: what it
// registered lives in it.
void load_plugin(const std::filesystem::path& library);

// The libraries loaded so far, in order (canonical paths).
const std::vector<std::filesystem::path>& loaded_plugins();

}  // namespace mhb

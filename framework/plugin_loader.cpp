#include "framework/plugin_loader.hpp"

#include <dlfcn.h>

#include <charconv>
#include <system_error>

#define BOOST_DLL_USE_STD_FS
#include <boost/dll/library_info.hpp>
#include <fmt/format.h>

#include "framework/plugin_interface.hpp"
#include "framework/registry.hpp"

namespace mhb {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path>& loaded() {
    static std::vector<fs::path> libraries;
    return libraries;
}

// The interface version in the file's exported symbols, read without loading it; -1 when it has none.
int interface_version_of(const fs::path& library) {
    std::vector<std::string> symbols;
    try {
        boost::dll::library_info info(library, false);
        symbols = info.symbols();
    } catch (const std::exception& e) {
        throw PluginLoadError(fmt::format("{}: not a shared library this program can load ({})", library.string(), e.what()));
    }
    const std::string prefix = MHBENCH_PLUGIN_SYMBOL_PREFIX;
    for (const auto& symbol : symbols) {
        if (!symbol.starts_with(prefix)) continue;
        int version = -1;
        const char* first = symbol.data() + prefix.size();
        const char* last = symbol.data() + symbol.size();
        const auto [end, error] = std::from_chars(first, last, version);
        if (error == std::errc() && end == last) return version;
    }
    return -1;
}

}  // namespace

int plugin_interface_version() { return MHBENCH_PLUGIN_INTERFACE_VERSION; }

const std::vector<fs::path>& loaded_plugins() { return loaded(); }

void load_plugin(const fs::path& library) {
    std::error_code ec;
    if (!fs::exists(library, ec)) throw PluginLoadError(fmt::format("{}: no such file", library.string()));
    if (fs::is_directory(library, ec))
        throw PluginLoadError(fmt::format("{}: is a directory; expected a plugin library (lib<name>.so)", library.string()));
    const fs::path file = fs::canonical(library);
    for (const auto& done : loaded())
        if (done == file) return;

    const int version = interface_version_of(file);
    if (version < 0)
        throw PluginLoadError(fmt::format(
            "{}: not an mhbench plugin: it has no interface version (symbol {}N); build it with "
            "target_link_libraries(<target> PRIVATE mhbench::plugin) after find_package(mhbench) (docs/plugins.md)",
            file.string(), MHBENCH_PLUGIN_SYMBOL_PREFIX));
    if (version != plugin_interface_version())
        throw PluginLoadError(fmt::format(
            "{}: built against mhbench plugin interface version {}, but this mhbench has interface version {}; "
            "rebuild the plugin against this installation",
            file.string(), version, plugin_interface_version()));

    const auto clashes_before = registration_clashes().size();
    set_registration_origin(file.string());
    // RTLD_NOW: an undefined symbol is reported here, with its name, not as a crash mid-run.
    // RTLD_GLOBAL: a later plugin may use what an earlier one defines (e.g. an effect's base class).
    void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_GLOBAL);
    set_registration_origin("built-in");
    if (!handle) {
        const char* reason = dlerror();
        throw PluginLoadError(fmt::format("{}: cannot load: {}", file.string(), reason ? reason : "unknown reason"));
    }
    // Never closed: the registries hold factories whose code lives in the library.
    loaded().push_back(file);
    const auto clashes = registration_clashes();
    if (clashes.size() > clashes_before) throw PluginLoadError(clashes[clashes_before]);
}

}  // namespace mhb

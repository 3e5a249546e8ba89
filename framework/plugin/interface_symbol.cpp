// Compiled into every plugin library through the mhbench::plugin CMake target (never into the core):
// the symbol framework/plugin_loader.cpp looks for, named after the interface version of the headers
// this plugin was compiled with. A function, not a variable: every loaded plugin defines it, and two
// definitions of a global variable under one name are an ODR violation to AddressSanitizer.
#include "framework/plugin_interface.hpp"

#define MHBENCH_SYMBOL_OF(version) mhbench_plugin_interface_v##version
#define MHBENCH_SYMBOL(version) MHBENCH_SYMBOL_OF(version)

extern "C" __attribute__((visibility("default"), used)) int MHBENCH_SYMBOL(MHBENCH_PLUGIN_INTERFACE_VERSION)() {
    return MHBENCH_PLUGIN_INTERFACE_VERSION;
}

#pragma once
// The interface a plugin library compiles against: the public headers that `cmake --install` puts in
// include/mhbench (registry, optimizer, problem, parameters, random, commands, the PMSM effect).
// Raise the version with any change to them that a plugin built before it would not survive: a
// class's layout, a virtual function, a signature, a registry's entry.
// 2: Evaluator gained the anytime recorder (a member, so its size changed).
#define MHBENCH_PLUGIN_INTERFACE_VERSION 2

// Each plugin library exports one symbol whose name carries the version it was built against
// (framework/plugin/interface_symbol.cpp, compiled into every target that links mhbench::plugin), so
// the program reads the version off the file before loading it: no code of a mismatched plugin runs.
#define MHBENCH_PLUGIN_SYMBOL_PREFIX "mhbench_plugin_interface_v"

#pragma once
// The interface a plugin library compiles against: the public headers that `cmake --install` puts in
// include/mhbench (registry, optimizer, problem, parameters, random, commands, the PMSM effect).
// Raise the version with any change to them that a plugin built before it would not survive: a
// class's layout, a virtual function, a signature, a registry's entry.
// tests/plugin_interface_test.cpp records a digest of the headers' code for each version and fails
// when the code changes while the version stays.
// 2: Evaluator gained the anytime recorder (a member, so its size changed).
// 3: the PMSM headers moved into rooms (machine/, data/; the old paths forward); effects/effect.hpp no
//    longer declares require_columns nor includes the measurement; LinearFlux left machine.hpp.
// 4: Effect gained its operating scale (a member) and narrow_range, range_end_meaning and
//    implausible_reason; plant_flux_model takes the plant's scale; the saturation law changed.
// 5: Effect gained is_size (a virtual: the parameters a detection limit is stated in).
// 6: Measurement gained theta_m (the shaft's mechanical angle, an optional column: its layout changed).
// 7: Effect gained law_accuracy (a virtual: the error its law is known to leave on real machines).
// 8: Effect gained unseen_bias (a virtual: what it does to the base parameters that no log shows).
// 9: ModelState gained ld and lq (the inductances of the present run, for terms proportional to them).
// 10: Effect's narrow_range became plausible_range, which may reach beyond the declared range.
// 11: Effect gained material_value (a virtual: a parameter's value in the machine's material).
// 12: Effect gained law_terms (a virtual: the separate terms of its law, which a search may drop).
// 13: Effect gained angle_orders (a virtual: the harmonics of the electrical angle its law makes).
// 14: Effect::unseen_bias returns an UnseenBias (its sentence and the base parameters it moves).
// 15: Measurement gained the drive's current loop (its bandwidth and delay: its layout changed).
// 16: Effect gained model_changes_inputs (a virtual: whether its later stages change the sensors' outputs).
#define MHBENCH_PLUGIN_INTERFACE_VERSION 16

// Each plugin library exports one symbol whose name carries the version it was built against
// (framework/plugin/interface_symbol.cpp, compiled into every target that links mhbench::plugin), so
// the program reads the version off the file before loading it: no code of a mismatched plugin runs.
#define MHBENCH_PLUGIN_SYMBOL_PREFIX "mhbench_plugin_interface_v"

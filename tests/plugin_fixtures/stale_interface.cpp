// What a plugin built by an mhbench of plugin interface 0 carries. Its registration would run if the
// program loaded it; the test checks the program refuses it first (the optimizer never appears).
#include "idle_optimizer.hpp"

extern "C" __attribute__((visibility("default"), used)) int mhbench_plugin_interface_v0() { return 0; }

namespace {
const bool registered = fixture::register_idle_optimizer("stale_optimizer", "registered only if the interface check were skipped");
}  // namespace

// libFuzzer harness: the flux map CSV (problems/pmsm/machine/flux_models.hpp).
// Build and run: docs/fuzzing.md.
#include "tests/fuzz/input_formats.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return mhb::fuzz::fuzz_one_input("flux_map", data, size);
}

// libFuzzer harness: the simulation profile (problems/pmsm/simulation/simulation_profile.hpp), parsed but never simulated.
// Build and run: docs/fuzzing.md.
#include "tests/fuzz/input_formats.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return mhb::fuzz::fuzz_one_input("simulation_profile", data, size);
}

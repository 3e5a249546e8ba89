// libFuzzer harness: the measurement CSV (problems/pmsm/data/measurement.hpp).
// Build and run: docs/fuzzing.md.
#include "tests/fuzz/input_formats.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return mhb::fuzz::fuzz_one_input("measurement", data, size);
}

// libFuzzer harness: the model spec such as base+delay(tau=150e-6) (problems/pmsm/model/model_spec.hpp).
// Build and run: docs/fuzzing.md.
#include "tests/fuzz/input_formats.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return mhb::fuzz::fuzz_one_input("model_spec", data, size);
}

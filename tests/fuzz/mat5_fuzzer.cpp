// libFuzzer harness: measurement MAT v5/v7 files, pmsm::read_binary_measurement as Mat5 (problems/pmsm/data/mat_file_reader.cpp).
// Build and run: docs/fuzzing.md.
#include "tests/fuzz/input_formats.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return mhb::fuzz::fuzz_one_input("mat5", data, size);
}

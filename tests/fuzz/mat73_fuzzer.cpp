// libFuzzer harness: measurement MAT v7.3 files, pmsm::read_binary_measurement as Mat73 (problems/pmsm/data/hdf5_file_reader.cpp).
// Build and run: docs/fuzzing.md.
#include "tests/fuzz/input_formats.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) { return mhb::fuzz::load_hdf5_reader(); }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return mhb::fuzz::fuzz_one_input("mat73", data, size);
}

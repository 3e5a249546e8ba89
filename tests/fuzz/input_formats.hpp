#pragma once
// The input formats the fuzzers drive, each reduced to "parse this text". The libFuzzer harnesses
// (tests/fuzz/*_fuzzer.cpp, clang only) and the regression test (tests/fuzz_regression_test.cpp,
// every compiler) share these entry points, so a file the fuzzer saved replays through exactly the
// code that failed on it.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace mhb::fuzz {

struct InputFormat {
    std::string_view name;  // also the directory of its regression files and seed corpus
    void (*parse)(const std::string& text);
};

// Every format, in a fixed order.
std::span<const InputFormat> input_formats();
// The format called `name`; std::out_of_range for any other name (a typo in a harness).
const InputFormat& input_format(std::string_view name);

enum class Verdict { accepted, refused };

// Parses `text`: accepted, or refused with one of the project's input errors (mhb::InputError, and
// mhb::UnknownPlugin, which the CLI reports the same way). Any other exception propagates: that is
// the bug the fuzzers look for.
Verdict accept_or_refuse(const InputFormat& format, const std::string& text);

// The body of LLVMFuzzerTestOneInput for the format `name`.
int fuzz_one_input(std::string_view name, const std::uint8_t* data, std::size_t size);

// The body of LLVMFuzzerInitialize for the formats libhdf5 reads (HDF5, MAT v7.3): loads the
// reader's library (libmhbench_hdf5.so) before the first input, so that libFuzzer lists it among
// the modules it takes coverage from when it starts. Returns 0.
int load_hdf5_reader();

}  // namespace mhb::fuzz

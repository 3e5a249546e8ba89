#pragma once
// The organisers' data of a CEC suite function (shift vectors, rotation matrices, shuffles), read
// from their text files once per process and shared read-only by every instance.
#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "framework/problem.hpp"

namespace mhb::cec {

// What one function at one dimension needs, for each of its components (one for simple and hybrid
// functions, up to ten for composition functions).
struct FunctionData {
    std::vector<Vector> shifts;                  // o_k, the first D numbers of line k of shift_data_N.txt
    std::vector<Matrix> rotations;               // M_k, D x D blocks of M_N_DD.txt, in file order
    std::vector<std::vector<int>> permutations;  // zero-based shuffles of shuffle_data_N_DD.txt
};

struct DataRequest {
    std::string suite;             // "cec2017" or "cec2022": the folder under the data directory
    int function = 0;              // N in the file names
    int dimension = 0;             // D
    int components = 1;            // how many shifts and rotations the function uses
    bool shuffled = false;         // whether it reads shuffle_data_N_DD.txt
    std::filesystem::path folder;  // empty: the data vendored with mhbench
};

// The data directory vendored with mhbench (problems/cec/data of the source tree), or, for an
// installed program, share/mhbench/cec beside it.
std::filesystem::path vendored_data_directory();

// The data of one function at one dimension, read on the first request in this process and shared
// by every later one. Throws InputError naming the file (and line) when a file is missing, short,
// or holds something other than numbers or a permutation.
std::shared_ptr<const FunctionData> function_data(const DataRequest& request);

// How many data files this process has opened (the tests check that each is read once).
std::size_t data_files_read();

}  // namespace mhb::cec

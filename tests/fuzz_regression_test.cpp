#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"
#include "tests/fuzz/input_formats.hpp"
#include "tests/measurement_file_writers.hpp"

namespace fs = std::filesystem;
using mhb::fuzz::Verdict;

namespace {

const fs::path regressions_directory = fs::path(MHBENCH_SOURCE_DIR) / "tests" / "fuzz" / "regressions";
// Valid files of every documented binary layout, which the binary fuzzers start from.
const fs::path seeds_directory = fs::path(MHBENCH_SOURCE_DIR) / "tests" / "fuzz" / "seeds";
// Inputs on which the fuzzers saw libhdf5 itself fault (docs/fuzzing.md, "Findings"). Not
// regressions: read in this process, as the harnesses read, they would end the test program.
const fs::path libhdf5_faults_directory = fs::path(MHBENCH_SOURCE_DIR) / "tests" / "fuzz" / "libhdf5_faults";

std::string file_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    REQUIRE(in);
    return {std::istreambuf_iterator<char>(in), {}};
}

// Sorted, so a failure names the same file first on every machine.
std::vector<fs::path> files_in(const fs::path& directory) {
    std::vector<fs::path> out;
    if (fs::is_directory(directory))
        for (const auto& entry : fs::directory_iterator(directory))
            if (entry.is_regular_file()) out.push_back(entry.path());
    std::sort(out.begin(), out.end());
    return out;
}

Verdict verdict_on(const std::string& format, const std::string& file) {
    return mhb::fuzz::accept_or_refuse(mhb::fuzz::input_format(format),
                                       file_bytes(regressions_directory / format / file));
}

}  // namespace

TEST_CASE("every fuzzer regression file is accepted or refused with an input error", "[fuzz]") {
    std::size_t replayed = 0;
    for (const auto& format : mhb::fuzz::input_formats())
        for (const auto& file : files_in(regressions_directory / format.name)) {
            INFO(file.string());
            // Anything but an input error escapes accept_or_refuse and fails here with its message.
            CHECK_NOTHROW(mhb::fuzz::accept_or_refuse(format, file_bytes(file)));
            ++replayed;
        }
    CHECK(replayed >= 6);
}

TEST_CASE("every regression directory is the name of an input format", "[fuzz]") {
    // A misspelt directory would otherwise be skipped without a word.
    for (const auto& entry : fs::directory_iterator(regressions_directory)) {
        INFO(entry.path().string());
        CHECK(entry.is_directory());
        CHECK_NOTHROW(mhb::fuzz::input_format(entry.path().filename().string()));
    }
}

TEST_CASE("the bad inputs named in issue 12 are refused, not accepted", "[fuzz]") {
    CHECK(verdict_on("simulation_profile", "integer_beyond_2_pow_53_rs.toml") == Verdict::refused);
    CHECK(verdict_on("simulation_profile", "integer_beyond_2_pow_53_speed.toml") == Verdict::refused);
    CHECK(verdict_on("measurement", "semicolon_separated.csv") == Verdict::refused);
    CHECK(verdict_on("measurement", "decimal_comma.csv") == Verdict::refused);
    CHECK(verdict_on("measurement", "binary_bytes.csv") == Verdict::refused);
    CHECK(verdict_on("experiment", "empty.toml") == Verdict::refused);
}

TEST_CASE("an experiment whose lists multiply into 10^8 variants is refused before they are expanded", "[fuzz]") {
    CHECK(verdict_on("experiment", "grid_of_10_pow_8_variants.toml") == Verdict::refused);
}

TEST_CASE("a MAT v7.3 number type declaring gigabytes a number is refused before libhdf5 allocates for one", "[fuzz]") {
    // Found by fuzz_mat73 as out-of-memory: H5Dread converted through a buffer of one stored number.
    CHECK(verdict_on("mat73", "u_q_floats_of_1.6_gb_each.mat") == Verdict::refused);
    CHECK(verdict_on("mat73", "t_floats_of_4_gb_each.mat") == Verdict::refused);
}

TEST_CASE("an HDF5 compact dataset holding fewer bytes than its shape and type take is refused before libhdf5 reads past them", "[fuzz]") {
    // Found by fuzz_hdf5 as a heap-buffer-overflow in libhdf5's H5D__compact_readvv (48 bytes read from 8).
    CHECK(verdict_on("hdf5", "t_compact_data_of_8_bytes_for_6_rows.h5") == Verdict::refused);
    // And a v7.3 cell's char array, read by its own H5Dread (fuzz_mat73: a segfault in H5VM_memcpyvv).
    CHECK(verdict_on("mat73", "segment_cell_compact_chars_past_their_block.mat") == Verdict::refused);
}

TEST_CASE("an HDF5 integer whose significant bits lie outside it is refused before libhdf5 converts it", "[fuzz]") {
    // Found by fuzz_hdf5 as a bus error in libhdf5's H5T__bit_copy: a 2-byte i_q whose bits start at bit 4096.
    CHECK(verdict_on("hdf5", "i_q_int16_bits_at_4096.h5") == Verdict::refused);
}

TEST_CASE("every input that made libhdf5 fault in a fuzzer is read or refused naming the file when read in a child process", "[fuzz]") {
    // What mhbench does with such a file outside the fuzzers: the reader in a child process with
    // limits. A fault that ends the child is a refusal saying which file and that the library
    // failed on it; an over-read that faults only under AddressSanitizer
    // (attribute_message_overread.mat) may leave the read to finish; a loop inside libhdf5
    // (global_heap_endless_loop.h5) is stopped by the time limit, here 5 s instead of the
    // reader's 600 s so that the suite does not wait for it.
    std::size_t replayed = 0;
    const mhb::pmsm::Hdf5Reader read = mhb::pmsm::hdf5_reader();  // loaded here, not in each child
    for (const auto& [format, layout] : {std::pair{"mat73", mhb::pmsm::Hdf5Layout::matlab}, std::pair{"hdf5", mhb::pmsm::Hdf5Layout::plain}})
        for (const auto& file : files_in(libhdf5_faults_directory / format)) {
            INFO(file.string());
            const std::string source = file.string();
            const mhb::pmsm::ColumnChoice choose = [&](const std::vector<std::string>& names) {
                return mhb::pmsm::bind_columns(names, {}, source, 0, "variable");
            };
            try {
                mhb::pmsm::read_in_child_process(source, "the HDF5 library", [&] { return read(file, choose, layout); }, 5);
            } catch (const mhb::InputError& e) {
                CHECK(e.file() == source);
            }
            ++replayed;
        }
    CHECK(replayed >= 5);
}

TEST_CASE("every binary fuzzer seed, a valid file of a documented layout, is accepted", "[fuzz]") {
    std::size_t accepted = 0;
    for (const std::string format : {"mat5", "mat73", "hdf5"}) {
        const auto files = files_in(seeds_directory / format);
        CHECK(files.size() >= 3);
        for (const auto& file : files) {
            INFO(file.string());
            CHECK(mhb::fuzz::accept_or_refuse(mhb::fuzz::input_format(format), file_bytes(file)) == Verdict::accepted);
            ++accepted;
        }
    }
    CHECK(accepted >= 9);
}

// Run by hand (`mhbench_tests "[.write_fuzz_seeds]"`) to write the seeds again into the source tree.
TEST_CASE("write the binary fuzzers' seeds", "[.write_fuzz_seeds]") {
    using mhb::testing::WrittenColumn;
    const std::vector<double> t{0, 1e-3, 2e-3, 3e-3, 4e-3, 5e-3}, i{0.5, 0.25, -1, 2, 1e-3, 3}, u{12, 11.5, -3, 4, 0, 7.25};
    const std::vector<double> numbers_segment{1, 1, 2, 2, 2, 3};
    const std::vector<std::string> text_segment{"id0", "id0", "id-1", "id-1", "\xC2\xB5", "id0"};
    auto log = [&](bool text) {
        return std::vector<WrittenColumn>{{"t", t, {}},   {"segment", text ? std::vector<double>{} : numbers_segment, text ? text_segment : std::vector<std::string>{}},
                                          {"i_d", i, {}}, {"i_q", i, {}}, {"u_d", u, {}}, {"u_q", u, {}}, {"omega_e", u, {}}};
    };
    for (const std::string format : {"mat5", "mat73", "hdf5"}) fs::create_directories(seeds_directory / format);
    mhb::testing::write_mat(seeds_directory / "mat5" / "v5_numbers.mat", MAT_FT_MAT5, log(false));
    mhb::testing::write_mat(seeds_directory / "mat5" / "v7_cell_segment.mat", MAT_FT_MAT5, log(true), "", MAT_COMPRESSION_ZLIB);
    mhb::testing::write_mat(seeds_directory / "mat5" / "v7_struct.mat", MAT_FT_MAT5, log(true), "log", MAT_COMPRESSION_ZLIB);
    mhb::testing::write_mat(seeds_directory / "mat5" / "v5_struct_cell_segment.mat", MAT_FT_MAT5, log(true), "log");
    mhb::testing::write_mat(seeds_directory / "mat73" / "v73_cell_segment.mat", MAT_FT_MAT73, log(true));
    mhb::testing::write_mat(seeds_directory / "mat73" / "v73_numbers.mat", MAT_FT_MAT73, log(false));
    mhb::testing::write_mat(seeds_directory / "mat73" / "v73_struct.mat", MAT_FT_MAT73, log(true), "log");
    // A char matrix of labels (rows "ab", "ab", "c", ...), as char(labels) saves them.
    for (const auto& [format, version] : {std::pair{"mat5", MAT_FT_MAT5}, std::pair{"mat73", MAT_FT_MAT73}}) {
        const auto path = seeds_directory / format / (std::string(format == std::string("mat5") ? "v5" : "v73") + "_char_matrix_segment.mat");
        mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, version);
        const char labels[] = {'a', 'a', 'c', 'c', 'c', 'a', 'b', 'b', ' ', ' ', ' ', 'b'};
        std::size_t dims[2] = {6, 2};
        matvar_t* v = Mat_VarCreate("segment", MAT_C_CHAR, MAT_T_UTF8, 2, dims, const_cast<char*>(labels), 0);
        Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
        for (const auto& c : log(false))
            if (c.name != "segment") {
                v = mhb::testing::mat_variable(c, true);
                Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
                Mat_VarFree(v);
            }
        Mat_Close(mat);
    }
    mhb::testing::write_hdf5(seeds_directory / "hdf5" / "root_datasets.h5", log(true));
    mhb::testing::write_hdf5(seeds_directory / "hdf5" / "one_group.h5", log(false), "bench");
    {
        H5::H5File file((seeds_directory / "hdf5" / "fixed_utf8_strings_int16.h5").string(), H5F_ACC_TRUNC);
        const hsize_t dims[2] = {6, 1};
        H5::StrType fixed(H5::PredType::C_S1, 4);
        fixed.setCset(H5T_CSET_UTF8);
        file.createDataSet("segment", fixed, H5::DataSpace(2, dims)).write("id0\0id0\0id1\0id1\0\xC2\xB5\0\0id0\0", fixed);
        const short counts[6] = {1, 2, 3, 4, 5, -6};
        for (const char* name : {"i_d", "i_q", "u_d", "u_q", "omega_e"})
            file.createDataSet(name, H5::PredType::STD_I16LE, H5::DataSpace(2, dims)).write(counts, H5::PredType::NATIVE_SHORT);
    }
}

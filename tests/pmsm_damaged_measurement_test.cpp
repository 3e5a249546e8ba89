// Measurement files a user's disk, a logger or a hostile sender may hand over: not regular files,
// files cut short inside a signature, columns that are passed over. Each is refused with one line
// that names the file, or read with its warnings shown (docs/data-format.md, "What the reader refuses").
#include <catch2/catch.hpp>

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <hdf5.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"
#include "tests/measurement_file_writers.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using mhb::testing::WrittenColumn;
namespace fs = std::filesystem;

namespace {

// The first 400 rows of the diagnosis drive: the valid log every damaged file starts from.
const Measurement& valid_log() {
    static const Measurement m = [] {
        std::vector<Eigen::Index> rows(400);
        for (Eigen::Index r = 0; r < 400; ++r) rows[static_cast<std::size_t>(r)] = r;
        return select_rows(mhb::pmsm::testing::diagnosis_data({}), rows);
    }();
    return m;
}

// The valid log's columns with segment as numbers (1, 2, ... by first appearance), as a bench
// numbers its operating points, or as text.
std::vector<WrittenColumn> log_columns(bool numeric_segment) {
    auto columns = mhb::testing::columns_of(valid_log());
    if (numeric_segment) {
        columns[1].labels.clear();
        for (Eigen::Index r = 0; r < valid_log().size(); ++r) columns[1].numbers.push_back(valid_log().segment[r] + 1.0);
    }
    return columns;
}

std::string bytes_of(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

void write_bytes(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

bool same_numbers(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return a.size() == b.size() && a == b; }
bool same_optional(const std::optional<Eigen::VectorXd>& a, const std::optional<Eigen::VectorXd>& b) {
    return a.has_value() == b.has_value() && (!a || same_numbers(*a, *b));
}
// Every column equal to the last bit, segments included.
bool same_measurement(const Measurement& a, const Measurement& b) {
    return same_numbers(a.i_d, b.i_d) && same_numbers(a.i_q, b.i_q) && same_numbers(a.u_d, b.u_d) && same_numbers(a.u_q, b.u_q) &&
           same_numbers(a.omega_e, b.omega_e) && same_optional(a.t, b.t) && same_optional(a.theta_e, b.theta_e) &&
           same_optional(a.temp_winding, b.temp_winding) && same_optional(a.temp_magnet, b.temp_magnet) &&
           a.segment_labels == b.segment_labels && a.segment.size() == b.segment.size() && a.segment == b.segment;
}

// The offsets and sizes of a MAT v5 file's top-level elements (tags included), little-endian.
std::vector<std::pair<std::size_t, std::size_t>> mat5_elements(const std::string& bytes) {
    std::vector<std::pair<std::size_t, std::size_t>> out;
    for (std::size_t at = 128; at + 8 <= bytes.size();) {
        std::uint32_t n = 0;
        std::memcpy(&n, bytes.data() + at + 4, 4);
        out.emplace_back(at, 8 + n);
        at += 8 + n;
    }
    return out;
}

// The valid files the damaged ones are made from: every layout, with numeric and text segments.
struct ValidSource {
    std::string name;
    bool compressed_mat5;
    std::function<void(const fs::path&)> write;
};

std::vector<ValidSource> valid_sources() {
    using mhb::testing::write_hdf5;
    using mhb::testing::write_mat;
    return {
        {"v5_numeric_segment.mat", false, [](const fs::path& p) { write_mat(p, MAT_FT_MAT5, log_columns(true)); }},
        {"v7_text_segment.mat", true, [](const fs::path& p) { write_mat(p, MAT_FT_MAT5, log_columns(false), "", MAT_COMPRESSION_ZLIB); }},
        {"v7_numeric_segment.mat", true, [](const fs::path& p) { write_mat(p, MAT_FT_MAT5, log_columns(true), "", MAT_COMPRESSION_ZLIB); }},
        {"v7_struct.mat", true, [](const fs::path& p) { write_mat(p, MAT_FT_MAT5, log_columns(false), "log", MAT_COMPRESSION_ZLIB); }},
        {"v73.mat", false, [](const fs::path& p) { write_mat(p, MAT_FT_MAT73, log_columns(false)); }},
        {"log.h5", false, [](const fs::path& p) { write_hdf5(p, log_columns(false)); }},
    };
}

// A `segment` dataset of UTF-8 strings, as h5py writes them: variable length, or fixed at the
// longest label's length and padded with NULs.
void write_utf8_segment(H5::Group& group, const std::vector<std::string>& labels, bool variable) {
    const hsize_t dims[1] = {labels.size()};
    std::size_t width = 1;
    for (const auto& l : labels) width = std::max(width, l.size());
    H5::StrType text(H5::PredType::C_S1, variable ? H5T_VARIABLE : width);
    text.setCset(H5T_CSET_UTF8);
    auto dataset = group.createDataSet("segment", text, H5::DataSpace(1, dims));
    if (variable) {
        std::vector<const char*> pointers;
        for (const auto& l : labels) pointers.push_back(l.c_str());
        dataset.write(pointers.data(), text);
    } else {
        std::string fixed;
        for (const auto& l : labels) fixed += l + std::string(width - l.size(), '\0');
        dataset.write(fixed.data(), text);
    }
}

// What reading a damaged file gave: refused naming it, or read.
struct Outcome {
    bool refused = false;
    std::string message;
    std::optional<Measurement> read;
};

Outcome read_damaged(const fs::path& path) {
    Outcome out;
    try {
        out.read = read_measurement(path);
    } catch (const InputError& e) {
        out.refused = true;
        out.message = e.what();
        CHECK(e.file() == path.string());
    }
    return out;
}

// Damaged copies of the valid file `bytes`: cut short at many lengths, and (for compressed MAT
// files, whose every variable carries a checksum) one byte flipped in each variable's stream.
std::vector<std::pair<std::string, std::string>> damaged_copies(const std::string& bytes, bool compressed_mat5) {
    std::vector<std::pair<std::string, std::string>> out;
    const std::size_t n = bytes.size();
    for (const std::size_t length : {std::size_t{4}, std::size_t{8}, std::size_t{64}, std::size_t{127}, std::size_t{128}, std::size_t{129},
                                     std::size_t{136}, n / 4, n / 2, 3 * n / 4, n - 9, n - 8, n - 1})
        out.emplace_back("cut_to_" + std::to_string(length), bytes.substr(0, length));
    if (compressed_mat5)
        for (const auto& [at, size] : mat5_elements(bytes))
            for (const std::size_t offset : {std::size_t{8}, std::size_t{10}, size / 2, size - 4, size - 1}) {
                std::string copy = bytes;
                copy[at + offset] = static_cast<char>(copy[at + offset] ^ 0x55);
                out.emplace_back("flip_at_" + std::to_string(at + offset), std::move(copy));
            }
    return out;
}

std::string refusal_of(const fs::path& path) {
    try {
        read_measurement(path);
    } catch (const InputError& e) {
        CHECK(e.file() == path.string());
        return e.message();
    }
    FAIL("the reader accepted " << path);
    return "";
}

}  // namespace

TEST_CASE("a FIFO given as the measurement file is refused before it is opened, so nothing waits for a writer",
          "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto fifo = dir.path() / "log.mat";
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
    // No writer ever opens it: a reader that opened it would block here for ever.
    CHECK(refusal_of(fifo) == "is a FIFO (named pipe); the measurement file must be a regular file (save the data to a file and give that)");
    CHECK(measurement_format(fifo) == MeasurementFormat::Csv);
    const auto run = mhb::testing::run_mhbench("fit --data " + fifo.string(), dir.path() / "log");
    CHECK(run.exit_code == 2);
    CHECK_THAT(run.output, Catch::Contains("error: " + fifo.string() + ": is a FIFO (named pipe)"));
    CHECK_THAT(refusal_of("/dev/null"), Catch::StartsWith("is a character device;"));
}

TEST_CASE("a file cut short inside an HDF5 signature or a MATLAB header is refused as that format, not read as CSV",
          "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto hdf5 = dir.write("cut.h5", "\x89HDF");
    CHECK(measurement_format(hdf5) == MeasurementFormat::Hdf5);
    CHECK_THAT(refusal_of(hdf5), !Catch::Contains("missing required column"));
    const auto mat = dir.write("cut.mat", "MATLAB 5.0 MAT");
    CHECK(measurement_format(mat) == MeasurementFormat::Mat5);
    CHECK(refusal_of(mat) == "a MAT file cut short: 14 bytes, less than a MAT file's 128-byte header");
    const auto mat73 = dir.write("cut73.mat", "MATLAB 7.3 MAT-file, Platform: GLNXA64");
    CHECK(measurement_format(mat73) == MeasurementFormat::Mat73);
    CHECK_THAT(refusal_of(mat73), Catch::Contains("cut short"));
}

TEST_CASE("fit and diagnose print the reader's warnings, a CSV column not used among them", "[pmsm][measurement][damaged][cli]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "drive.csv";
    write_measurement(csv, mhb::pmsm::testing::diagnosis_data({}));
    // The same log with a column mhbench does not know, as a bench logs its DC-link voltage.
    const std::string text = mhb::testing::read_file(csv);
    std::string with_extra;
    std::size_t line_start = 0;
    for (std::size_t k = 0; line_start < text.size(); ++k) {
        const std::size_t end = text.find('\n', line_start);
        with_extra += text.substr(line_start, end - line_start) + (k == 0 ? ",u_dc" : ",48") + "\n";
        line_start = end + 1;
    }
    const auto extra = dir.write("extra.csv", with_extra);
    for (const std::string command : {"fit", "diagnose"}) {
        const auto run = mhb::testing::run_mhbench(command + " --data " + extra.string(), dir.path() / "log");
        INFO(run.output);
        CHECK(run.exit_code == 0);
        CHECK_THAT(run.output, Catch::Contains("warning: " + extra.string() + ": column 'u_dc' is not used by mhbench and was ignored"));
    }
    const auto clean = mhb::testing::run_mhbench("fit --data " + csv.string(), dir.path() / "log");
    CHECK(clean.exit_code == 0);
    CHECK_THAT(clean.output, !Catch::Contains("warning:"));
}

TEST_CASE("damaged MAT and HDF5 files are refused naming the file or read exactly as the valid one, never a wrong answer",
          "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto sources = valid_sources();
    std::size_t refused = 0, read_same = 0;
    for (const auto& source : sources) {
        const auto valid_path = dir.path() / source.name;
        source.write(valid_path);
        const Measurement valid = read_measurement(valid_path);
        REQUIRE(valid.size() == 400);
        for (const auto& [what, bytes] : damaged_copies(bytes_of(valid_path), source.compressed_mat5)) {
            const auto path = dir.path() / (what + "_" + source.name);
            write_bytes(path, bytes);
            INFO(path.filename());
            const auto outcome = read_damaged(path);
            if (outcome.refused) {
                ++refused;
                // One line that names the file; no library's raw text as the whole message.
                CHECK(outcome.message.find('\n') == std::string::npos);
                CHECK_THAT(outcome.message, Catch::StartsWith(path.string() + ": "));
            } else {
                REQUIRE(outcome.read);
                CHECK(same_measurement(*outcome.read, valid));
                ++read_same;
            }
            fs::remove(path);
        }
    }
    INFO("refused " << refused << ", read as the valid file " << read_same);
    CHECK(refused > 100);
}

TEST_CASE("a damaged compressed stream and a file missing its last byte (wrong answers with exit 0 in issue 26) are refused",
          "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto path = dir.path() / "log.mat";
    mhb::testing::write_mat(path, MAT_FT_MAT5, log_columns(true), "", MAT_COMPRESSION_ZLIB);
    const std::string bytes = bytes_of(path);
    const auto elements = mat5_elements(bytes);
    REQUIRE(elements.size() == 10);
    SECTION("one byte inside i_q's compressed stream: zlib's check fails and the variable is named") {
        std::string copy = bytes;
        const auto [at, size] = elements[4];
        copy[at + size / 2] = static_cast<char>(copy[at + size / 2] ^ 0x01);
        write_bytes(path, copy);
        const auto e = read_damaged(path);
        REQUIRE(e.refused);
        CHECK_THAT(e.message, Catch::StartsWith(path.string() + ": variable 5 (at byte " + std::to_string(at) +
                                                "), named 'i_q' as far as it can be read: its compressed data is damaged (zlib: "));
    }
    SECTION("the last byte missing: the last variable is cut short") {
        write_bytes(path, bytes.substr(0, bytes.size() - 1));
        const auto e = read_damaged(path);
        REQUIRE(e.refused);
        CHECK(e.message == path.string() + ": variable 10 (at byte " + std::to_string(elements[9].first) + ") declares " +
                               std::to_string(elements[9].second - 8) + " bytes but the file ends " + std::to_string(elements[9].second - 9) +
                               " bytes after its tag: the file is cut short");
    }
}

TEST_CASE("each value finite and each numeric segment label a whole number, or the row is refused", "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    auto columns = log_columns(true);
    SECTION("a segment label of -5.5e303, and one of 2.5") {
        for (const double label : {-5.5e303, 2.5, 65536.5}) {
            columns[1].numbers[399] = label;
            for (const auto& path : {dir.path() / "log.mat", dir.path() / "log.h5"}) {
                if (path.extension() == ".mat") mhb::testing::write_mat(path, MAT_FT_MAT5, columns);
                else mhb::testing::write_hdf5(path, columns);
                const auto e = read_damaged(path);
                REQUIRE(e.refused);
                CHECK_THAT(e.message, Catch::StartsWith(path.string() + ": segment: row 400: segment label "));
                CHECK_THAT(e.message, Catch::Contains("is not a whole number in [-2147483648, 2147483647]"));
            }
        }
        columns[1].numbers[399] = 65536;
        mhb::testing::write_mat(dir.path() / "log.mat", MAT_FT_MAT5, columns);
        CHECK(read_measurement(dir.path() / "log.mat").segment_labels.back() == "65536");
    }
    SECTION("infinity and NaN in a MAT v7.3 file name the row") {
        columns[4].numbers[16] = std::numeric_limits<double>::infinity();
        mhb::testing::write_mat(dir.path() / "log.mat", MAT_FT_MAT73, columns);
        CHECK(read_damaged(dir.path() / "log.mat").message == (dir.path() / "log.mat").string() + ": i_q: row 17: not a finite number: inf");
    }
}

TEST_CASE("a damaged name is a variable not used and shown as a warning, a damaged required name is refused listing the names",
          "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    for (const auto version : {MAT_FT_MAT5, MAT_FT_MAT73}) {
        const auto path = dir.path() / "log.mat";
        mhb::testing::write_mat(path, version, log_columns(false));
        std::string bytes = bytes_of(path);
        // The byte edit a damaged disk makes: the name's characters, nothing else.
        const auto at = bytes.find("segment");
        REQUIRE(at != std::string::npos);
        bytes[at + 5] = '~';
        write_bytes(path, bytes);
        const auto m = read_measurement(path);
        CHECK_FALSE(m.has_segments());
        CHECK(std::find(m.warnings.begin(), m.warnings.end(), path.string() + ": variable 'segme~t' is not used by mhbench and was ignored") !=
              m.warnings.end());
        const auto iq = bytes.find("i_q");
        REQUIRE(iq != std::string::npos);
        bytes[iq + 1] = '~';
        write_bytes(path, bytes);
        const auto e = read_damaged(path);
        REQUIRE(e.refused);
        CHECK_THAT(e.message, Catch::Contains("i_q: missing required variable"));
        CHECK_THAT(e.message, Catch::Contains(", i~q, "));
    }
}

TEST_CASE("declared sizes are checked before anything is allocated or read", "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto columns = log_columns(false);
    SECTION("a MAT v5 vector whose dimensions were damaged to 2^31 - 1 rows") {
        const auto path = dir.path() / "log.mat";
        mhb::testing::write_mat(path, MAT_FT_MAT5, columns);
        std::string bytes = bytes_of(path);
        // i_d's dimensions: the int32 400 after its array flags, at 8 (tag) + 16 (flags) + 8 (dims tag).
        const auto at = mat5_elements(bytes)[3].first + 8 + 16 + 8;
        const std::int32_t huge = std::numeric_limits<std::int32_t>::max();
        std::memcpy(bytes.data() + at, &huge, 4);
        write_bytes(path, bytes);
        CHECK(read_damaged(path).message == path.string() + ": i_d: 2147483647 rows; the limit is 5000000 rows");
    }
    SECTION("HDF5: a used dataset of 2^28 rows never written, and one of 400 rows never written") {
        const auto path = dir.path() / "log.h5";
        for (const hsize_t rows : {hsize_t{1} << 28, hsize_t{400}}) {
            {
                H5::H5File file(path.string(), H5F_ACC_TRUNC);
                for (const auto& c : columns)
                    if (c.name != "i_q") mhb::testing::write_hdf5_column(file, c);
                const hsize_t dims[2] = {1, rows};
                file.createDataSet("i_q", H5::PredType::IEEE_F64LE, H5::DataSpace(2, dims));
            }
            const auto e = read_damaged(path);
            REQUIRE(e.refused);
            CHECK(e.message == path.string() + (rows > 5'000'000 ? ": i_q: 268435456 rows; the limit is 5000000 rows"
                                                                 : ": i_q: declares 400 rows but holds data for none of them (never written, or the file is damaged)"));
        }
    }
    SECTION("HDF5: an unused dataset of 400 fixed-length strings of 1 GB each is never read") {
        const auto path = dir.path() / "log.h5";
        {
            H5::H5File file(path.string(), H5F_ACC_TRUNC);
            for (const auto& c : columns) mhb::testing::write_hdf5_column(file, c);
            const hsize_t dims[1] = {400};
            file.createDataSet("notes", H5::StrType(H5::PredType::C_S1, std::size_t{1} << 30), H5::DataSpace(1, dims));
        }
        const auto m = read_measurement(path);
        CHECK(same_measurement(m, read_measurement([&] {
                                   const auto clean = dir.path() / "clean.h5";
                                   mhb::testing::write_hdf5(clean, columns);
                                   return clean;
                               }())));
        CHECK(m.warnings == std::vector<std::string>{path.string() + ": variable 'notes' is not used by mhbench and was ignored"});
        // Used, its width is refused before anything is read.
        const auto e = read_damaged(path);
        const auto mapped = [&] {
            try {
                read_measurement(path, parse_column_map("segment=notes", "command line", "--columns"));
            } catch (const InputError& error) {
                return std::string(error.message());
            }
            return std::string("accepted");
        }();
        CHECK(mapped == "fixed-length strings of 1073741824 bytes; mhbench reads labels of at most 4096 bytes");
    }
}

TEST_CASE("HDF5 string segments in UTF-8 (h5py's default), variable and fixed length, read as text", "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto path = dir.path() / "utf8.h5";
    const std::vector<std::string> labels{"id0", "id0", "\xC2\xB5" "A_\xE2\x86\x92", "id0"};
    for (const bool variable : {true, false}) {
        {
            H5::H5File file(path.string(), H5F_ACC_TRUNC);
            write_utf8_segment(file, labels, variable);
            const std::vector<double> ones(labels.size(), 1.0);
            for (const char* name : {"i_d", "i_q", "u_d", "u_q", "omega_e"})
                mhb::testing::write_hdf5_column(file, {name, ones, {}});
        }
        INFO((variable ? "variable" : "fixed") << "-length");
        const auto m = read_measurement(path);
        CHECK(m.segment_labels == std::vector<std::string>{"id0", labels[2]});
        CHECK(m.segment == Eigen::Vector4i(0, 0, 1, 0));
    }
}

TEST_CASE("HDF5 links and storage outside the file are never followed", "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    const auto columns = log_columns(false);
    const auto path = dir.path() / "log.h5";
    const auto fifo = dir.path() / "elsewhere.h5";
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
    {
        H5::H5File file(path.string(), H5F_ACC_TRUNC);
        for (const auto& c : columns)
            if (c.name != "temp_magnet") mhb::testing::write_hdf5_column(file, c);
        // Into a FIFO that no one writes: following it would wait for ever.
        REQUIRE(H5Lcreate_external(fifo.c_str(), "/temp_magnet", file.getId(), "magnet", H5P_DEFAULT, H5P_DEFAULT) >= 0);
    }
    {
        // A soft link to the external link: following the soft link must not follow the external one.
        H5::H5File file(path.string(), H5F_ACC_RDWR);
        REQUIRE(H5Lcreate_soft("/magnet", file.getId(), "magnet_again", H5P_DEFAULT, H5P_DEFAULT) >= 0);
    }
    const auto m = read_measurement(path);
    CHECK_FALSE(m.temp_magnet);
    CHECK(std::find(m.warnings.begin(), m.warnings.end(),
                    path.string() + ": 'magnet' is an external link into another file and was not followed") != m.warnings.end());
    CHECK(std::find(m.warnings.begin(), m.warnings.end(),
                    path.string() + ": 'magnet_again' is neither a dataset nor a group and was ignored") != m.warnings.end());
    try {
        read_measurement(path, parse_column_map("temp_magnet=magnet_again", "command line", "--columns"));
        FAIL("accepted");
    } catch (const InputError& e) {
        // Not a variable: the soft link leads nowhere the reader may go.
        CHECK_THAT(e.message(), Catch::StartsWith("no such variable (mapped to temp_magnet by --columns)"));
    }
    try {
        read_measurement(path, parse_column_map("temp_magnet=magnet", "command line", "--columns"));
        FAIL("accepted");
    } catch (const InputError& e) {
        CHECK(e.message() == "an external link into another file; mhbench reads only what this file holds (copy the data into it)");
    }
    // A dataset whose raw data lives in an external file (here the FIFO).
    {
        H5::H5File file(path.string(), H5F_ACC_TRUNC);
        for (const auto& c : columns)
            if (c.name != "u_d") mhb::testing::write_hdf5_column(file, c);
        H5::DSetCreatPropList creation;
        creation.setExternal(fifo.c_str(), 0, 400 * 8);
        const hsize_t dims[1] = {400};
        file.createDataSet("u_d", H5::PredType::IEEE_F64LE, H5::DataSpace(1, dims), creation);
    }
    const auto e = read_damaged(path);
    CHECK(e.message == path.string() + ": u_d: its data is stored in external files; mhbench reads only what this file holds");
}

TEST_CASE("thousands of unused variables are listed in one pass and read in well under a second", "[pmsm][measurement][damaged]") {
    mhb::testing::TemporaryDirectory dir;
    auto columns = log_columns(false);
    const std::size_t extra = 20'000;
    for (std::size_t k = 0; k < extra; ++k) columns.push_back({"unused_" + std::to_string(k), {1.0, 2.0}, {}});
    const auto mat = dir.path() / "many.mat", h5 = dir.path() / "many.h5";
    mhb::testing::write_mat(mat, MAT_FT_MAT5, columns, "", MAT_COMPRESSION_ZLIB);
    mhb::testing::write_hdf5(h5, columns);
    for (const auto& path : {mat, h5}) {
        const auto start = std::chrono::steady_clock::now();
        const auto m = read_measurement(path);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        INFO(path.filename() << ": " << seconds << " s");
        CHECK(m.size() == 400);
        CHECK(m.warnings.size() == extra);
        // Quadratic listing took 60 s for a v5 file like this one; linear takes tens of milliseconds.
        CHECK(seconds < 10.0);
    }
}

TEST_CASE("a fault inside libhdf5 on a damaged file is a refusal naming the file, not the end of the program",
          "[pmsm][measurement][damaged]") {
    // Found by fuzz_hdf5: a global-heap object whose declared size makes libhdf5 1.10.8's H5HG_read
    // copy past its buffer while it measures the segment labels (a segfault, before and after).
    const fs::path path = fs::path(MHBENCH_SOURCE_DIR) / "tests" / "damaged_files" / "hdf5_global_heap_overread.h5";
    const auto e = read_damaged(path);
    REQUIRE(e.refused);
    CHECK_THAT(e.message, Catch::StartsWith(path.string() + ": the HDF5 library failed on it ("));
    CHECK_THAT(e.message, Catch::Contains("in the process that reads the file); the file is damaged"));
    // The same reader in this process is what the fuzzer ran; the program goes on after a refusal.
    CHECK(read_measurement(fs::path(MHBENCH_SOURCE_DIR) / "tests" / "fuzz" / "seeds" / "hdf5" / "root_datasets.h5").size() == 6);
}

TEST_CASE("the child process that reads a file hands back its columns or its refusal, and is stopped by its limits",
          "[pmsm][measurement][damaged]") {
    SECTION("columns, numbers and labels, bit for bit") {
        FileColumns sent;
        sent.columns.push_back({"Id", "i_d", Eigen::Vector3d(0.1, -2e-300, 3.5), {}});
        TextColumn labels;
        const char* texts[] = {"a", "b\xC2\xB5", "a"};
        labels.rows.resize(3);
        for (int r = 0; r < 3; ++r) labels.rows[r] = labels.index_of(texts[r]);
        sent.columns.push_back({"op", "segment", {}, labels});
        sent.unused = {"x", "y"};
        sent.notes = {"a note"};
        const auto got = read_in_child_process("f.h5", "the library", [&] { return sent; });
        REQUIRE(got.columns.size() == 2);
        CHECK(got.columns[0].name == "Id");
        CHECK(got.columns[0].column == "i_d");
        CHECK(got.columns[0].numbers == sent.columns[0].numbers);
        REQUIRE(got.columns[1].labels);
        CHECK(got.columns[1].labels->texts == labels.texts);
        CHECK(got.columns[1].labels->rows == labels.rows);
        CHECK(got.unused == sent.unused);
        CHECK(got.notes == sent.notes);
    }
    auto refusal_in_child = [](const std::function<FileColumns()>& read, unsigned seconds = 600) {
        try {
            read_in_child_process("f.h5", "the library", read, seconds);
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    CHECK(refusal_in_child([]() -> FileColumns { throw InputError("f.h5", 0, "u_q", "row 2: not a finite number: nan"); }) ==
          "f.h5: u_q: row 2: not a finite number: nan");
    CHECK(refusal_in_child([]() -> FileColumns {
              raise(SIGABRT);
              return {};
          }) == "f.h5: the library failed on it (Aborted, in the process that reads the file); the file is damaged or not what it claims to be "
                "(save or copy it again)");
    CHECK(refusal_in_child(
              []() -> FileColumns {
                  while (true) pause();
              },
              1) == "f.h5: reading it took over 1 s and was stopped (the library looping on a damaged file?)");
}

// Run by hand, `MHBENCH_DAMAGED_CORPUS=DIR mhbench_tests "[.write_damaged_corpus]"`: the damaged
// files of the tests above in DIR, and DIR/manifest.tsv giving each file's class, the valid file it
// was made from and the --columns it is read with. tests/damaged_files/count_outcomes.py runs
// `mhbench fit` on each and counts the outcomes per class (docs/data-format.md, "Damaged files").
TEST_CASE("write the damaged-file corpus", "[.write_damaged_corpus]") {
    const char* target = std::getenv("MHBENCH_DAMAGED_CORPUS");
    REQUIRE(target);
    const fs::path dir(target);
    fs::create_directories(dir);
    std::ofstream manifest(dir / "manifest.tsv");
    auto entry = [&](const std::string& file, const std::string& kind, const std::string& source, const std::string& columns = "") {
        manifest << file << '\t' << kind << '\t' << source << '\t' << columns << '\n';
    };
    for (const auto& source : valid_sources()) {
        source.write(dir / source.name);
        entry(source.name, "valid", source.name);
        const std::string bytes = bytes_of(dir / source.name);
        for (const auto& [what, damaged] : damaged_copies(bytes, source.compressed_mat5)) {
            write_bytes(dir / (what + "_" + source.name), damaged);
            entry(what + "_" + source.name, what.starts_with("cut") ? "cut short" : "compressed byte flipped", source.name);
        }
        // A byte flipped in the exponent of a raw (uncompressed) double: no checksum covers it.
        if (!source.compressed_mat5) {
            const double value = valid_log().i_q[200];
            const auto at = bytes.find(std::string(reinterpret_cast<const char*>(&value), sizeof value));
            REQUIRE(at != std::string::npos);
            std::string copy = bytes;
            copy[at + 7] = static_cast<char>(copy[at + 7] ^ 0x10);
            write_bytes(dir / ("raw_flip_" + source.name), copy);
            entry("raw_flip_" + source.name, "raw number byte flipped", source.name);
        }
    }
    auto columns = log_columns(true);
    for (const double label : {-5.5e303, 2.5}) {
        columns[1].numbers[399] = label;
        const std::string name = "label_" + std::to_string(label).substr(0, 4) + ".mat";
        mhb::testing::write_mat(dir / name, MAT_FT_MAT5, columns);
        entry(name, "segment label not a whole number", "v5_numeric_segment.mat");
    }
    columns = log_columns(true);
    columns[4].numbers[16] = std::numeric_limits<double>::infinity();
    mhb::testing::write_mat(dir / "inf_i_q.mat", MAT_FT_MAT73, columns);
    entry("inf_i_q.mat", "value not finite", "v73.mat");
    columns[4].numbers[16] = std::nan("");
    mhb::testing::write_hdf5(dir / "nan_i_q.h5", columns);
    entry("nan_i_q.h5", "value not finite", "log.h5");
    for (const auto& source : {std::string("v5_numeric_segment.mat"), std::string("v73.mat"), std::string("log.h5")}) {
        std::string bytes = bytes_of(dir / source);
        bytes[bytes.find("segment") + 5] = '~';
        write_bytes(dir / ("renamed_segment_" + source), bytes);
        entry("renamed_segment_" + source, "segment name damaged", source);
    }
    REQUIRE(mkfifo((dir / "fifo.mat").c_str(), 0600) == 0);
    entry("fifo.mat", "FIFO", "");
    {
        H5::H5File file((dir / "external_link_to_fifo.h5").string(), H5F_ACC_TRUNC);
        for (const auto& c : log_columns(false)) mhb::testing::write_hdf5_column(file, c);
        REQUIRE(H5Lcreate_external((dir / "fifo.mat").c_str(), "/x", file.getId(), "elsewhere", H5P_DEFAULT, H5P_DEFAULT) >= 0);
    }
    entry("external_link_to_fifo.h5", "external link to a FIFO", "log.h5");
    for (const std::size_t extra : {std::size_t{4000}, std::size_t{20'000}}) {
        auto many = log_columns(false);
        for (std::size_t k = 0; k < extra; ++k) many.push_back({"unused_" + std::to_string(k), {1.0, 2.0}, {}});
        const std::string n = std::to_string(extra);
        mhb::testing::write_mat(dir / ("many_" + n + "_v7.mat"), MAT_FT_MAT5, many, "", MAT_COMPRESSION_ZLIB);
        mhb::testing::write_mat(dir / ("many_" + n + "_v73.mat"), MAT_FT_MAT73, many);
        mhb::testing::write_hdf5(dir / ("many_" + n + ".h5"), many);
        entry("many_" + n + "_v7.mat", n + " unused variables", "v7_text_segment.mat");
        entry("many_" + n + "_v73.mat", n + " unused variables", "v73.mat");
        entry("many_" + n + ".h5", n + " unused variables", "log.h5");
    }
    {
        H5::H5File file((dir / "unused_1GB_strings.h5").string(), H5F_ACC_TRUNC);
        for (const auto& c : log_columns(false)) mhb::testing::write_hdf5_column(file, c);
        const hsize_t dims[1] = {3};
        const H5::StrType wide(H5::PredType::C_S1, std::size_t{1} << 30);
        // Declared, never written (chunked storage allocates nothing): 3 GB in a file of a few kB.
        H5::DSetCreatPropList creation;
        const hsize_t chunk[1] = {1};
        creation.setChunk(1, chunk);
        file.createDataSet("notes", wide, H5::DataSpace(1, dims), creation);
    }
    entry("unused_1GB_strings.h5", "unused dataset declaring 3 GB", "log.h5");
    {
        const auto path = dir / "unwritten_2_pow_28.mat";
        mhb::testing::write_mat(path, MAT_FT_MAT73, log_columns(false));
        H5::H5File file(path.string(), H5F_ACC_RDWR);
        const hsize_t dims[2] = {hsize_t{1} << 28, 1};
        H5::DSetCreatPropList creation;
        const hsize_t chunk[2] = {4096, 1};
        creation.setChunk(2, chunk);
        auto dataset = file.createDataSet("big", H5::PredType::IEEE_F64LE, H5::DataSpace(2, dims), creation);
        const H5::StrType name(H5::PredType::C_S1, 6);
        dataset.createAttribute("MATLAB_class", name, H5::DataSpace()).write(name, "double");
    }
    entry("unwritten_2_pow_28.mat", "variable declaring 2^28 rows never written", "v73.mat", "i_q=big");
    entry("unwritten_2_pow_28.mat", "unused variable declaring 2^28 rows never written", "v73.mat");
    for (const bool variable : {true, false}) {
        const std::string name = std::string("utf8_") + (variable ? "variable" : "fixed") + ".h5";
        H5::H5File file((dir / name).string(), H5F_ACC_TRUNC);
        for (const auto& c : log_columns(false))
            if (c.name != "segment") mhb::testing::write_hdf5_column(file, c);
        write_utf8_segment(file, log_columns(false)[1].labels, variable);
        entry(name, "UTF-8 segment strings", "log.h5");
    }
}

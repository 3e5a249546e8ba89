// MAT (v5, v7, v7.3) and HDF5 measurement files, the column map and unit scaling. The files are
// written here with matio's and HDF5's own write APIs, so the tests need no MATLAB.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <H5Cpp.h>
#include <matio.h>
#include <nlohmann/json.hpp>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "tests/measurement_file_writers.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::testing;
using namespace mhb::pmsm;
namespace fs = std::filesystem;

namespace {

void check_identical(const Measurement& a, const Measurement& b) {
    REQUIRE(a.size() == b.size());
    // Eigen's == compares every element with ==; NaN cannot occur (both readers refuse it).
    CHECK(a.i_d == b.i_d);
    CHECK(a.i_q == b.i_q);
    CHECK(a.u_d == b.u_d);
    CHECK(a.u_q == b.u_q);
    CHECK(a.omega_e == b.omega_e);
    REQUIRE(a.t.has_value() == b.t.has_value());
    if (a.t) CHECK(*a.t == *b.t);
    REQUIRE(a.theta_e.has_value() == b.theta_e.has_value());
    if (a.theta_e) CHECK(*a.theta_e == *b.theta_e);
    REQUIRE(a.temp_winding.has_value() == b.temp_winding.has_value());
    if (a.temp_winding) CHECK(*a.temp_winding == *b.temp_winding);
    REQUIRE(a.temp_magnet.has_value() == b.temp_magnet.has_value());
    if (a.temp_magnet) CHECK(*a.temp_magnet == *b.temp_magnet);
    CHECK(a.segment_labels == b.segment_labels);
    CHECK(a.segment == b.segment);
}

std::uint32_t little_endian_u32(const std::string& s, std::size_t at) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(s[at + static_cast<std::size_t>(k)]);
    return v;
}

// Reverses each `width`-byte value in s[at, at + n).
void swap_values(std::string& s, std::size_t at, std::size_t n, std::size_t width) {
    for (std::size_t k = 0; k + width <= n; k += width) std::reverse(s.begin() + static_cast<std::ptrdiff_t>(at + k), s.begin() + static_cast<std::ptrdiff_t>(at + k + width));
}

std::size_t mat_type_width(std::uint32_t type) {
    switch (type) {
        case 3: case 4: case 17: return 2;          // int16, uint16, utf16
        case 5: case 6: case 7: case 18: return 4;  // int32, uint32, single, utf32
        case 9: case 12: case 13: return 8;         // double, int64, uint64
        default: return 1;
    }
}

// The elements in s[at, end) of a little-endian MAT v5 file turned big-endian in place: every tag,
// and every value by its own width; arrays (miMATRIX) element by element, cells and fields included.
void swap_mat_elements(std::string& s, std::size_t at, std::size_t end) {
    while (at + 8 <= end) {
        const std::uint32_t first = little_endian_u32(s, at);
        if (first >> 16) {  // small element: type and size in one word, the data in the next four bytes
            swap_values(s, at, 4, 4);
            swap_values(s, at + 4, first >> 16, mat_type_width(first & 0xFFFF));
            at += 8;
            continue;
        }
        const std::uint32_t n = little_endian_u32(s, at + 4);
        swap_values(s, at, 8, 4);
        if (first == 14) swap_mat_elements(s, at + 8, at + 8 + n);
        else swap_values(s, at + 8, n, mat_type_width(first));
        at += 8 + n + (8 - n % 8) % 8;
    }
}

InputError refusal(const fs::path& path, const ColumnMap& map = {}) {
    try {
        read_measurement(path, map);
    } catch (const InputError& e) {
        return e;
    }
    FAIL("the reader accepted " << path);
    throw std::logic_error("unreachable");
}

const Measurement& drive() { return mhb::pmsm::testing::diagnosis_data({}); }

}  // namespace

TEST_CASE("MAT v5, v7, v7.3 and HDF5 files give the same doubles as the CSV, bit for bit", "[pmsm][measurement][formats]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "drive.csv";
    write_measurement(csv, drive());
    const Measurement reference = read_measurement(csv);
    const auto columns = columns_of(drive());

    SECTION("MAT v5") {
        write_mat(dir.path() / "drive.mat", MAT_FT_MAT5, columns);
        CHECK(measurement_format(dir.path() / "drive.mat") == MeasurementFormat::Mat5);
        const auto m = read_measurement(dir.path() / "drive.mat");
        check_identical(m, reference);
        CHECK(m.warnings.empty());
    }
    SECTION("MAT v7 (v5 compressed)") {
        write_mat(dir.path() / "drive.mat", MAT_FT_MAT5, columns, "", MAT_COMPRESSION_ZLIB);
        check_identical(read_measurement(dir.path() / "drive.mat"), reference);
    }
    SECTION("MAT v7.3") {
        write_mat(dir.path() / "drive.mat", MAT_FT_MAT73, columns);
        CHECK(measurement_format(dir.path() / "drive.mat") == MeasurementFormat::Mat73);
        check_identical(read_measurement(dir.path() / "drive.mat"), reference);
    }
    SECTION("the fields of a MAT file's only struct, v5 and v7.3") {
        for (const auto version : {MAT_FT_MAT5, MAT_FT_MAT73}) {
            write_mat(dir.path() / "struct.mat", version, columns, "log");
            check_identical(read_measurement(dir.path() / "struct.mat"), reference);
        }
    }
    SECTION("HDF5, datasets at the root") {
        write_hdf5(dir.path() / "drive.h5", columns);
        CHECK(measurement_format(dir.path() / "drive.h5") == MeasurementFormat::Hdf5);
        check_identical(read_measurement(dir.path() / "drive.h5"), reference);
    }
    SECTION("HDF5, datasets in the root's only group") {
        write_hdf5(dir.path() / "drive.h5", columns, "bench");
        check_identical(read_measurement(dir.path() / "drive.h5"), reference);
    }
    SECTION("the content decides, not the name: HDF5 named .csv, CSV named .mat") {
        write_hdf5(dir.path() / "really_hdf5.csv", columns);
        CHECK(measurement_format(dir.path() / "really_hdf5.csv") == MeasurementFormat::Hdf5);
        check_identical(read_measurement(dir.path() / "really_hdf5.csv"), reference);
        fs::copy_file(csv, dir.path() / "really_csv.mat");
        CHECK(measurement_format(dir.path() / "really_csv.mat") == MeasurementFormat::Csv);
        check_identical(read_measurement(dir.path() / "really_csv.mat"), reference);
    }
}

TEST_CASE("a MAT v5 file written on a big-endian machine reads as the same file written on a little-endian one", "[pmsm][measurement][formats]") {
    mhb::testing::TemporaryDirectory dir;
    for (const bool in_struct : {false, true}) {
        const auto little = dir.path() / "little.mat", big = dir.path() / "big.mat";
        write_mat(little, MAT_FT_MAT5, columns_of(drive()), in_struct ? "log" : "");
        std::string bytes = mhb::testing::read_file(little);
        REQUIRE(bytes.substr(126, 2) == "IM");
        bytes[126] = 'M';
        bytes[127] = 'I';
        std::swap(bytes[124], bytes[125]);  // the version, 0x0100
        swap_mat_elements(bytes, 128, bytes.size());
        std::ofstream(big, std::ios::binary) << bytes;
        INFO((in_struct ? "one struct" : "variables"));
        check_identical(read_measurement(big), read_measurement(little));
    }
}

TEST_CASE("numeric segments and other layouts: integers, char matrices, fixed-length strings", "[pmsm][measurement][formats]") {
    mhb::testing::TemporaryDirectory dir;
    const std::vector<double> ones{1.0, 2.0, 3.0};
    SECTION("a numeric segment in HDF5 is labelled by its number, as in CSV") {
        auto columns = std::vector<WrittenColumn>{{"segment", {4, 4, 7}, {}}, {"i_d", ones, {}}, {"i_q", ones, {}},
                                                  {"u_d", ones, {}},           {"u_q", ones, {}}, {"omega_e", ones, {}}};
        write_hdf5(dir.path() / "n.h5", columns);
        const auto m = read_measurement(dir.path() / "n.h5");
        CHECK(m.segment_labels == std::vector<std::string>{"4", "7"});
        const auto csv = read_measurement(
            dir.write("n.csv", "segment,i_d,i_q,u_d,u_q,omega_e\n4,1,1,1,1,1\n4,2,2,2,2,2\n7,3,3,3,3,3\n"));
        check_identical(m, csv);
    }
    SECTION("a char matrix of labels in MAT, one label per row, padding dropped") {
        const char labels[] = {'a', 'a', 'b', 'x', 'x', 'x', ' ', ' ', 'c'};  // column-major rows "ax", "ax", "bxc"
        mat_t* mat = Mat_CreateVer((dir.path() / "chars.mat").c_str(), nullptr, MAT_FT_MAT5);
        std::size_t dims[2] = {3, 3};
        matvar_t* v = Mat_VarCreate("segment", MAT_C_CHAR, MAT_T_UTF8, 2, dims, const_cast<char*>(labels), 0);
        Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
        for (const char* name : {"i_d", "i_q", "u_d", "u_q", "omega_e"}) {
            v = mat_variable({name, ones, {}}, true);
            Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
            Mat_VarFree(v);
        }
        Mat_Close(mat);
        const auto m = read_measurement(dir.path() / "chars.mat");
        CHECK(m.segment_labels == std::vector<std::string>{"ax", "bxc"});
        CHECK(m.segment == Eigen::Vector3i(0, 0, 1));
    }
    SECTION("fixed-length HDF5 strings and integer datasets; a row vector in MAT") {
        H5::H5File file((dir.path() / "fixed.h5").string(), H5F_ACC_TRUNC);
        const hsize_t dims[1] = {3};
        const H5::StrType fixed(H5::PredType::C_S1, 4);
        const char text[] = "ab\0\0ab\0\0cde ";
        file.createDataSet("segment", fixed, H5::DataSpace(1, dims)).write(text, fixed);
        const int counts[3] = {1, 2, 3};
        for (const char* name : {"i_d", "i_q", "u_d", "u_q", "omega_e"})
            file.createDataSet(name, H5::PredType::STD_I16LE, H5::DataSpace(1, dims)).write(counts, H5::PredType::NATIVE_INT);
        file.close();
        const auto m = read_measurement(dir.path() / "fixed.h5");
        CHECK(m.segment_labels == std::vector<std::string>{"ab", "cde"});
        CHECK(m.omega_e == Eigen::Vector3d(1, 2, 3));
    }
}

TEST_CASE("HDF5 string labels longer than a read slab, as a vector or a one-column matrix, read back row by row", "[pmsm][measurement][formats]") {
    // The reader takes variable-length strings 65536 rows at a time; 150001 rows end in a short slab.
    const std::size_t n = 150'001;
    std::vector<std::string> labels(n);
    for (std::size_t r = 0; r < n; ++r) labels[r] = "op" + std::to_string(r * 7 / n) + (r % 2 ? "" : "_even");
    std::vector<double> numbers(n);
    for (std::size_t r = 0; r < n; ++r) numbers[r] = static_cast<double>(r) * 0.5;
    mhb::testing::TemporaryDirectory dir;
    for (const std::vector<hsize_t>& shape : {std::vector<hsize_t>{n}, std::vector<hsize_t>{n, 1}, std::vector<hsize_t>{1, n}}) {
        INFO(shape.size() << "-dimensional, first extent " << shape[0]);
        const auto path = dir.path() / "labels.h5";
        {
            H5::H5File file(path.string(), H5F_ACC_TRUNC);
            const H5::StrType text(H5::PredType::C_S1, H5T_VARIABLE);
            std::vector<const char*> pointers;
            for (const auto& l : labels) pointers.push_back(l.c_str());
            file.createDataSet("segment", text, H5::DataSpace(static_cast<int>(shape.size()), shape.data())).write(pointers.data(), text);
            const hsize_t dims[1] = {n};
            for (const char* name : {"i_d", "i_q", "u_d", "u_q", "omega_e"})
                file.createDataSet(name, H5::PredType::IEEE_F64LE, H5::DataSpace(1, dims)).write(numbers.data(), H5::PredType::NATIVE_DOUBLE);
        }
        const auto m = read_measurement(path);
        REQUIRE(m.size() == static_cast<Eigen::Index>(n));
        CHECK(m.segment_labels.size() == 14);
        CHECK(labels_of(m) == labels);
        CHECK(m.u_q[static_cast<Eigen::Index>(n - 1)] == numbers.back());
    }
}

TEST_CASE("the column map reads a user's names and units from CSV, MAT and HDF5 alike", "[pmsm][measurement][formats]") {
    mhb::testing::TemporaryDirectory dir;
    // Logged as a bench would: mA, mV, mechanical rpm, degrees, kelvin, milliseconds.
    const std::vector<double> id_mA{-1500.0, 0.25, 2000.0}, iq_mA{100.0, 250.5, 300.0}, ud_mV{-12.5, 0.0, 4.25},
        uq_mV{5300.0, 5200.0, 5100.0}, rpm{10.0, 20.0, 30.0}, deg{0.0, 90.0, 359.0}, kelvin{293.15, 300.0, 310.5},
        ms{0.0, 0.4, 0.8};
    const std::vector<WrittenColumn> columns{{"time_ms", ms, {}},     {"Id_meas", id_mA, {}}, {"Iq_meas", iq_mA, {}},
                                             {"Vd_ref", ud_mV, {}},   {"Vq_ref", uq_mV, {}}, {"speed", rpm, {}},
                                             {"angle", deg, {}},      {"T_wind", kelvin, {}}, {"op", {}, {"a", "a", "b"}}};
    const std::string map_text =
        "t=time_ms[ms],i_d=Id_meas[mA],i_q=Iq_meas[mA],u_d=Vd_ref[mV],u_q=Vq_ref[mV],omega_e=speed[rpm],"
        "theta_e=angle[deg],temp_winding=T_wind[K],segment=op";
    auto map = parse_column_map(map_text, "command line", "--columns");
    map.pole_pairs = 16;

    write_mat(dir.path() / "bench.mat", MAT_FT_MAT5, columns);
    const auto m = read_measurement(dir.path() / "bench.mat", map);
    for (int r = 0; r < 3; ++r) {
        INFO("row " << r);
        CHECK(m.i_d[r] == id_mA[r] / 1000.0);
        CHECK(m.i_q[r] == iq_mA[r] / 1000.0);
        CHECK(m.u_d[r] == ud_mV[r] / 1000.0);
        CHECK(m.u_q[r] == uq_mV[r] / 1000.0);
        CHECK(m.omega_e[r] == rpm[r] * (std::numbers::pi / 30.0 * 16));
        CHECK((*m.theta_e)[r] == deg[r] * (std::numbers::pi / 180.0));
        CHECK((*m.temp_winding)[r] == kelvin[r] - 273.15);
        CHECK((*m.t)[r] == ms[r] / 1000.0);
    }
    CHECK(m.segment_labels == std::vector<std::string>{"a", "b"});
    CHECK(m.omega_e[1] == Approx(20.0 * 16 * 2 * std::numbers::pi / 60.0));

    write_mat(dir.path() / "bench73.mat", MAT_FT_MAT73, columns);
    check_identical(read_measurement(dir.path() / "bench73.mat", map), m);
    write_hdf5(dir.path() / "bench.h5", columns);
    check_identical(read_measurement(dir.path() / "bench.h5", map), m);
    const auto csv = dir.write("bench.csv",
                               "time_ms,Id_meas,Iq_meas,Vd_ref,Vq_ref,speed,angle,T_wind,op\n"
                               "0,-1500,100,-12.5,5300,10,0,293.15,a\n"
                               "0.4,0.25,250.5,0,5200,20,90,300,a\n"
                               "0.8,2000,300,4.25,5100,30,359,310.5,b\n");
    check_identical(read_measurement(csv, map), m);

    SECTION("the same map as a TOML file; the command line wins per column") {
        const auto toml = dir.write("map.toml",
                                    "pole_pairs = 16\n[columns]\nt = \"time_ms[ms]\"\ni_d = \"Id_meas[mA]\"\ni_q = \"Iq_meas[mA]\"\n"
                                    "u_d = \"Vd_ref[mV]\"\nu_q = \"Vq_ref[mV]\"\nomega_e = \"speed[rpm]\"\ntheta_e = \"angle[deg]\"\n"
                                    "temp_winding = \"T_wind[K]\"\nsegment = \"op\"\n");
        check_identical(read_measurement(dir.path() / "bench.mat", column_map_from_options("", toml.string(), 0)), m);
        const auto with_override = column_map_from_options("omega_e=speed[rpm]", toml.string(), 8);
        CHECK(read_measurement(dir.path() / "bench.mat", with_override).omega_e[2] == 30.0 * (std::numbers::pi / 30.0 * 8));
    }
    SECTION("a unit on a column that keeps mhbench's name") {
        const auto plain = dir.write("plain.csv", "i_d,i_q,u_d,u_q,omega_e\n1500,1,1,1,1\n");
        CHECK(read_measurement(plain, parse_column_map("i_d[mA]", "command line", "--columns")).i_d[0] == 1.5);
        const auto same = dir.write("same.csv", "i_d,i_q,u_d,u_q,omega_e,temp_magnet\n1,1,1,1,1,20\n");
        CHECK((*read_measurement(same, column_map_from_options("temp_magnet[degC]", "", 0)).temp_magnet)[0] == 20.0);
    }
}

TEST_CASE("each refusal of a binary file names the file, the variable and the row", "[pmsm][measurement][formats]") {
    mhb::testing::TemporaryDirectory dir;
    const std::vector<double> ones{1.0, 2.0, 3.0};
    auto base = [&] {
        return std::vector<WrittenColumn>{{"i_d", ones, {}}, {"i_q", ones, {}}, {"u_d", ones, {}}, {"u_q", ones, {}}, {"omega_e", ones, {}}};
    };
    const auto path = dir.path() / "bad.mat";
    SECTION("a non-finite value names its row") {
        auto columns = base();
        columns[3].numbers[1] = std::nan("");
        write_mat(path, MAT_FT_MAT5, columns);
        const auto e = refusal(path);
        CHECK(e.file() == path.string());
        CHECK(e.field() == "u_q");
        CHECK(e.message() == "row 2: not a finite number: nan");
        write_hdf5(dir.path() / "bad.h5", columns);
        CHECK(refusal(dir.path() / "bad.h5").message() == "row 2: not a finite number: nan");
    }
    SECTION("a missing variable: the ones present and the closest name") {
        auto columns = base();
        columns[2].name = "U_d";
        // v7.3 is HDF5, which lists names in byte order.
        write_mat(path, MAT_FT_MAT73, columns);
        const auto e = refusal(path);
        INFO(e.what());
        CHECK(e.field() == "u_d");
        CHECK(e.message().find("missing required variable") != std::string::npos);
        CHECK(e.message().find("the file has: U_d, i_d, i_q, omega_e, u_q") != std::string::npos);
        CHECK(e.message().find("did you mean 'U_d'?") != std::string::npos);
    }
    SECTION("a mapped variable that is absent") {
        auto columns = base();
        columns[0].name = "Id_meas";
        write_mat(path, MAT_FT_MAT5, columns);
        const auto e = refusal(path, parse_column_map("i_d=Id_mes", "command line", "--columns"));
        CHECK(e.field() == "Id_mes");
        CHECK(e.message().find("no such variable (mapped to i_d by --columns); did you mean 'Id_meas'?") != std::string::npos);
        CHECK(read_measurement(path, parse_column_map("i_d=Id_meas", "command line", "--columns")).i_d[2] == 3.0);
    }
    SECTION("columns of different lengths") {
        auto columns = base();
        columns[4].numbers.push_back(4.0);
        write_hdf5(dir.path() / "bad.h5", columns);
        const auto e = refusal(dir.path() / "bad.h5");
        CHECK(e.field() == "omega_e");
        CHECK(e.message() == "4 rows, but i_d has 3; every column must have one value per row");
    }
    SECTION("a matrix where a vector belongs; an unused matrix is only a warning") {
        mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
        for (const auto& c : base()) {
            matvar_t* v = mat_variable(c, true);
            Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
            Mat_VarFree(v);
        }
        const double block[6] = {1, 2, 3, 4, 5, 6};
        std::size_t dims[2] = {3, 2};
        matvar_t* v = Mat_VarCreate("temps", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, const_cast<double*>(block), 0);
        Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE);
        Mat_VarFree(v);
        Mat_Close(mat);
        const auto m = read_measurement(path);
        REQUIRE(m.warnings.size() == 1);
        CHECK(m.warnings[0] == path.string() + ": variable 'temps' is not used by mhbench and was ignored");
        const auto e = refusal(path, parse_column_map("temp_winding=temps", "command line", "--columns"));
        CHECK(e.field() == "temps (temp_winding)");
        CHECK(e.message() == "a 3x2 matrix, not a vector");
    }
    SECTION("text where numbers belong, and an empty segment label") {
        auto columns = base();
        columns[1].numbers.clear();
        columns[1].labels = {"x", "y", "z"};
        write_hdf5(dir.path() / "bad.h5", columns);
        CHECK(refusal(dir.path() / "bad.h5").message() == "holds text; mhbench reads numbers here (only segment may be text)");
        columns = base();
        columns.push_back({"op", {}, {"a", "", "b"}});
        write_mat(path, MAT_FT_MAT5, columns);
        const auto e = refusal(path, parse_column_map("segment=op", "command line", "--columns"));
        CHECK(e.field() == "op (segment)");
        CHECK(e.message() == "row 2: empty segment label");
    }
    SECTION("a value the unit conversion takes beyond the range of a double") {
        auto columns = base();
        columns[4].numbers[2] = 1.7e308;
        write_hdf5(dir.path() / "fast.h5", columns);
        auto map = parse_column_map("omega_e[rpm]", "command line", "--columns");
        map.pole_pairs = 16;
        const auto e = refusal(dir.path() / "fast.h5", map);
        CHECK(e.field() == "omega_e");
        CHECK(e.message() == "row 3: 1.7e+308 rpm is beyond the range of a double after conversion");
    }
    SECTION("HDF5 without datasets at the root and with several groups") {
        {
            H5::H5File file((dir.path() / "groups.h5").string(), H5F_ACC_TRUNC);
            file.createGroup("a");
            file.createGroup("b");
        }
        const auto e = refusal(dir.path() / "groups.h5");
        CHECK(e.message() == "no datasets at the root but 2 groups (a, b); mhbench reads the datasets at the root or in a single group");
    }
    SECTION("damaged files are named as such, with the library's reason") {
        std::string bytes = "\x89HDF\r\n\x1a\n";
        bytes += std::string(100, '\x07');
        dir.write("broken.h5", bytes);
        const auto e = refusal(dir.path() / "broken.h5");
        CHECK(e.message().starts_with("not a readable HDF5 file: "));
        dir.write("broken.mat", "MATLAB 5.0 MAT-file, truncated");
        CHECK(refusal(dir.path() / "broken.mat").message() == "a MAT file cut short: 30 bytes, less than a MAT file's 128-byte header");
        dir.write("v4.mat", "MATLAB 4 something");
        CHECK(refusal(dir.path() / "v4.mat").message().find("neither v5/v7 nor v7.3") != std::string::npos);
        dir.write("other.bin", std::string("\x7f" "ELF\x02\x01\x01\0\0\0", 10));
        CHECK(refusal(dir.path() / "other.bin").message() == "binary data that is neither CSV text, a MAT file (v5, v7, v7.3) nor HDF5");
    }
}

TEST_CASE("the column map itself is checked, naming the option or the file and line", "[pmsm][measurement][formats]") {
    auto refused = [](const std::function<void()>& f) {
        try {
            f();
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        FAIL("accepted");
        return std::string();
    };
    CHECK(refused([] { parse_column_map("i_dd=Id", "command line", "--columns"); })
              .starts_with("command line: --columns: unknown mhbench column 'i_dd'; did you mean 'i_d'?"));
    CHECK(refused([] { parse_column_map("i_d=Id[kA]", "command line", "--columns"); }) ==
          "command line: --columns: i_d: unknown unit 'kA' (accepted: A (mhbench's own), mA)");
    CHECK(refused([] { parse_column_map("i_d=Id,i_d=Iq", "command line", "--columns"); }) ==
          "command line: --columns: i_d is mapped twice");
    CHECK(refused([] { column_map_from_options("i_d=X,i_q=X", "", 0); }) ==
          "--columns: i_q: 'X' is already the source of i_d; each file column feeds one mhbench column");
    CHECK(refused([] { column_map_from_options("omega_e=speed[rpm]", "", 0); })
              .starts_with("--columns: omega_e: rpm is converted to electrical rad/s with the pole-pair count"));
    CHECK(refused([] { parse_column_map("i_d=", "command line", "--columns"); }) ==
          "command line: --columns: 'i_d': no source name after '='");

    mhb::testing::TemporaryDirectory dir;
    const auto bad_key = dir.write("map.toml", "pole_pair = 4\n");
    CHECK(refused([&] { read_column_map_file(bad_key); }).starts_with(bad_key.string() + ":1: pole_pair: unknown key 'pole_pair'; did you mean 'pole_pairs'?"));
    const auto bad_unit = dir.write("unit.toml", "[columns]\ni_d = \"Id\"\nu_d = \"Ud[kV]\"\n");
    CHECK(refused([&] { read_column_map_file(bad_unit); }) ==
          bad_unit.string() + ":3: columns.u_d: u_d: unknown unit 'kV' (accepted: V (mhbench's own), mV)");
    const auto bad_pairs = dir.write("pairs.toml", "pole_pairs = 0\n");
    CHECK(refused([&] { read_column_map_file(bad_pairs); }) == bad_pairs.string() + ":1: pole_pairs: expects a whole number in [1, 1000]");
}

TEST_CASE("mhbench fit on a MAT file with --columns gives the CSV's parameters", "[pmsm][measurement][formats][cli]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "drive.csv";
    write_measurement(csv, drive());
    // A renamed copy, as a bench's logger names the signals.
    write_mat(dir.path() / "drive.mat", MAT_FT_MAT73,
              columns_of(drive(), {{"i_d", "Id_meas"}, {"u_q", "Vq_ref"}, {"omega_e", "speed_el"}, {"segment", "op"}}));
    const auto from_csv = mhb::testing::run_mhbench("fit --data " + csv.string() + " --json " + (dir.path() / "csv.json").string(), dir.path() / "log");
    INFO(from_csv.output);
    REQUIRE(from_csv.exit_code == 0);
    const auto from_mat = mhb::testing::run_mhbench("fit --data " + (dir.path() / "drive.mat").string() +
                                                   " --columns i_d=Id_meas,u_q=Vq_ref,omega_e=speed_el,segment=op --json " +
                                                   (dir.path() / "mat.json").string(),
                                               dir.path() / "log");
    INFO(from_mat.output);
    REQUIRE(from_mat.exit_code == 0);
    const auto a = nlohmann::json::parse(mhb::testing::read_file(dir.path() / "csv.json"));
    const auto b = nlohmann::json::parse(mhb::testing::read_file(dir.path() / "mat.json"));
    CHECK(a["parameters"] == b["parameters"]);
    CHECK(a["rms"] == b["rms"]);

    const auto typo = mhb::testing::run_mhbench("fit --data " + (dir.path() / "drive.mat").string() + " --columns i_d=Id_mess", dir.path() / "log");
    CHECK(typo.exit_code == 2);
    CHECK(typo.output.find("error: " + (dir.path() / "drive.mat").string() +
                           ": Id_mess: no such variable (mapped to i_d by --columns); did you mean 'Id_meas'?") != std::string::npos);
    const auto no_pairs = mhb::testing::run_mhbench("diagnose --data " + csv.string() + " --columns omega_e[rpm]", dir.path() / "log");
    CHECK(no_pairs.exit_code == 2);
    CHECK(no_pairs.output.find("rpm is converted to electrical rad/s with the pole-pair count") != std::string::npos);
}

TEST_CASE("diagnose suggests next commands that read the file with the same column map", "[pmsm][measurement][formats][cli]") {
    mhb::testing::TemporaryDirectory dir;
    const auto h5 = dir.path() / "offset.h5";
    write_hdf5(h5, columns_of(mhb::pmsm::testing::diagnosis_data({{"encoder_offset", {}}}), {{"theta_e", "angle"}}), "bench");
    const auto run = mhb::testing::run_mhbench("diagnose --data " + h5.string() + " --columns theta_e=angle --report " +
                                                   (dir.path() / "report").string(),
                                               dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    const std::string next = "mhbench fit --data " + h5.string() + " --columns theta_e=angle --model base+encoder_offset";
    CHECK(run.output.find("next: " + next) != std::string::npos);
    CHECK(mhb::testing::read_file(dir.path() / "report" / "report.md").find(next) != std::string::npos);
}

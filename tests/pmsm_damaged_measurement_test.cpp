// Measurement files a user's disk, a logger or a hostile sender may hand over: not regular files,
// files cut short inside a signature, columns that are passed over. Each is refused with one line
// that names the file, or read with its warnings shown (docs/data-format.md, "What the reader refuses").
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <filesystem>
#include <string>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;
namespace fs = std::filesystem;

namespace {

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

TEST_CASE("fit and diagnose print the reader's warnings: a CSV column not used is named", "[pmsm][measurement][damaged][cli]") {
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

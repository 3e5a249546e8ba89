// The parts of mhbench built as libraries of their own (framework/optional_library.hpp): a command
// that does not need one starts without it and the libraries it brings; one that does loads it from
// beside the core library it runs, and without it says which file is missing.
#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

#include "problems/pmsm/data/measurement.hpp"
#include "tests/measurement_file_writers.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::testing;
namespace fs = std::filesystem;

namespace {

// The drive of Table 3 as an HDF5 file, written with HDF5's own C++ API.
fs::path paper_drive_as_hdf5(const fs::path& directory) {
    const auto m = pmsm::read_measurement(fs::path(MHBENCH_SOURCE_DIR) / "experiments/pmsm/paper_data.csv");
    const auto path = directory / "drive.h5";
    write_hdf5(path, {{"i_d", values(m.i_d), {}},
                      {"i_q", values(m.i_q), {}},
                      {"u_d", values(m.u_d), {}},
                      {"u_q", values(m.u_q), {}},
                      {"omega_e", values(m.omega_e), {}}});
    return path;
}

// The files the dynamic loader opened for `argv` (glibc's LD_DEBUG=files), with the program's output.
CliRun run_with_loader_trace(const std::vector<std::string>& argv, const fs::path& log) {
    std::vector<std::string> traced{"env", "LD_DEBUG=files"};
    traced.insert(traced.end(), argv.begin(), argv.end());
    return run_command(traced, log);
}

}  // namespace

TEST_CASE("mhbench loads libhdf5 only for a command that reads an HDF5 file, from beside its core library") {
    TemporaryDirectory dir;
    const auto version = run_with_loader_trace({MHBENCH_CLI, "--version"}, dir.path() / "version.log");
    INFO(version.output);
    REQUIRE(version.exit_code == 0);
    CHECK(version.output.find("libmhbench.so") != std::string::npos);  // the trace is there
    CHECK(version.output.find("libhdf5") == std::string::npos);
    CHECK(version.output.find("libcurl") == std::string::npos);

    const auto file = paper_drive_as_hdf5(dir.path());
    const auto fit = run_with_loader_trace({MHBENCH_CLI, "fit", "--data", file.string(), "--model", "base"}, dir.path() / "fit.log");
    INFO(fit.output);
    REQUIRE(fit.exit_code == 0);
    const std::string module = (fs::path(MHBENCH_BUILD_DIR) / "libmhbench_hdf5.so").string();
    CHECK(fit.output.find("file=" + module) != std::string::npos);
    CHECK(fit.output.find("libhdf5_serial.so") != std::string::npos);
}

TEST_CASE("an installed mhbench without its HDF5 library reads CSV and names the missing file for HDF5") {
    TemporaryDirectory dir;
    const fs::path prefix = dir.path() / "prefix";
    const auto install = run_command({MHBENCH_CMAKE, "--install", MHBENCH_BUILD_DIR, "--prefix", prefix.string()}, dir.path() / "install.log");
    INFO(install.output);
    REQUIRE(install.exit_code == 0);
    fs::path module;
    for (const auto& entry : fs::recursive_directory_iterator(prefix))
        if (entry.path().filename() == "libmhbench_hdf5.so") module = entry.path();
    REQUIRE(!module.empty());
    const std::string program = (prefix / "bin" / "mhbench").string();
    const auto file = paper_drive_as_hdf5(dir.path());

    // Installed whole, the program reads HDF5 with the library it was installed with.
    const auto whole = run_with_loader_trace({program, "fit", "--data", file.string(), "--model", "base"}, dir.path() / "whole.log");
    INFO(whole.output);
    REQUIRE(whole.exit_code == 0);
    CHECK(whole.output.find("file=" + module.string()) != std::string::npos);

    fs::remove(module);
    const auto csv = run_command({program, "fit", "--data", MHBENCH_SOURCE_DIR "/experiments/pmsm/paper_data.csv", "--model", "base"},
                                 dir.path() / "csv.log");
    INFO(csv.output);
    CHECK(csv.exit_code == 0);
    const auto hdf5 = run_command({program, "fit", "--data", file.string(), "--model", "base"}, dir.path() / "hdf5.log");
    INFO(hdf5.output);
    CHECK(hdf5.exit_code == 2);
    CHECK(hdf5.output.find("error: cannot load mhbench's libmhbench_hdf5.so: " + module.string()) != std::string::npos);
}

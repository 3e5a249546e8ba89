#include "tests/fuzz/input_formats.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <unistd.h>

#include "framework/experiment_config.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"
#include "problems/pmsm/model/model_spec.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"

namespace mhb::fuzz {
namespace {

void parse_experiment_text(const std::string& text) { parse_experiment(text, "fuzz.toml", PluginLoading::record_only); }

// Parsing only: a valid profile may ask for minutes of simulation, which would read as a hang.
// The base directory is never touched while parsing (the plant reads a flux map when it is built).
void parse_profile_text(const std::string& text) { pmsm::parse_simulation_profile(text, "fuzz.toml", "."); }

void parse_measurement_text(const std::string& text) { pmsm::parse_measurement(text, "fuzz.csv"); }

// The binary readers take a path (HDF5 opens files itself), so the bytes go to a file of this
// process's own, read as the format whatever its first bytes, then removed.
void parse_binary_file(const std::string& bytes, pmsm::MeasurementFormat format, const char* suffix) {
    const auto path = std::filesystem::temp_directory_path() / ("mhbench-fuzz-" + std::to_string(getpid()) + suffix);
    std::ofstream(path, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    struct Removal {
        const std::filesystem::path& path;
        ~Removal() {
            std::error_code ec;
            std::filesystem::remove(path, ec);
        }
    } removal{path};
    // In this process: the fuzzer looks for the faults a child process would turn into refusals.
    pmsm::read_binary_measurement(path, format, {}, pmsm::Isolation::in_process);
}

void parse_mat5_file(const std::string& bytes) { parse_binary_file(bytes, pmsm::MeasurementFormat::Mat5, ".mat"); }
void parse_mat73_file(const std::string& bytes) { parse_binary_file(bytes, pmsm::MeasurementFormat::Mat73, ".mat"); }
void parse_hdf5_file(const std::string& bytes) { parse_binary_file(bytes, pmsm::MeasurementFormat::Hdf5, ".h5"); }

// A typical magnet flux; the parser only checks the map, the value scales it later.
void parse_flux_map_text(const std::string& text) { pmsm::FluxMap::parse(text, "fuzz.csv", 0.1); }

void parse_model_spec_text(const std::string& text) { pmsm::parse_model_spec(text); }

constexpr std::array formats{
    InputFormat{"experiment", parse_experiment_text},
    InputFormat{"simulation_profile", parse_profile_text},
    InputFormat{"measurement", parse_measurement_text},
    InputFormat{"flux_map", parse_flux_map_text},
    InputFormat{"model_spec", parse_model_spec_text},
    InputFormat{"mat5", parse_mat5_file},
    InputFormat{"mat73", parse_mat73_file},
    InputFormat{"hdf5", parse_hdf5_file},
};

}  // namespace

std::span<const InputFormat> input_formats() { return formats; }

const InputFormat& input_format(std::string_view name) {
    for (const auto& format : formats)
        if (format.name == name) return format;
    throw std::out_of_range("no input format named " + std::string(name));
}

Verdict accept_or_refuse(const InputFormat& format, const std::string& text) {
    try {
        format.parse(text);
        return Verdict::accepted;
    } catch (const InputError&) {
        return Verdict::refused;
    } catch (const UnknownPlugin&) {
        return Verdict::refused;
    }
}

int fuzz_one_input(std::string_view name, const std::uint8_t* data, std::size_t size) {
    static const InputFormat& format = input_format(name);
    accept_or_refuse(format, std::string(reinterpret_cast<const char*>(data), size));
    return 0;
}

}  // namespace mhb::fuzz

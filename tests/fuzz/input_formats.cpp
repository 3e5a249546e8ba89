#include "tests/fuzz/input_formats.hpp"

#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fcntl.h>
#include <hdf5.h>
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
// process's own, read as the format whatever its first bytes. The file is made once and rewritten
// in place for each input: creating and removing one per input (open, unlink and the file system's
// bookkeeping) took about a tenth of fuzz_mat5's time.
class ScratchFile {
public:
    explicit ScratchFile(const char* suffix)
        : path_(std::filesystem::temp_directory_path() / ("mhbench-fuzz-" + std::to_string(getpid()) + suffix)),
          fd_(::open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600)) {
        if (fd_ < 0) throw std::runtime_error("cannot make the fuzzer's file " + path_.string() + ": " + std::strerror(errno));
    }
    ~ScratchFile() {
        ::close(fd_);
        std::error_code ec;
        std::filesystem::remove(path_, ec);
    }
    ScratchFile(const ScratchFile&) = delete;
    ScratchFile& operator=(const ScratchFile&) = delete;

    // The path of the file, now holding exactly `bytes`.
    const std::filesystem::path& holding(const std::string& bytes) {
        for (std::size_t at = 0; at < bytes.size();) {
            const ssize_t n = ::pwrite(fd_, bytes.data() + at, bytes.size() - at, static_cast<off_t>(at));
            if (n < 0 && errno == EINTR) continue;
            if (n <= 0) throw std::runtime_error("cannot write the fuzzer's file " + path_.string() + ": " + std::strerror(errno));
            at += static_cast<std::size_t>(n);
        }
        if (::ftruncate(fd_, static_cast<off_t>(bytes.size())) != 0)
            throw std::runtime_error("cannot cut the fuzzer's file " + path_.string() + ": " + std::strerror(errno));
        return path_;
    }

private:
    std::filesystem::path path_;
    int fd_;
};

void parse_binary_file(const std::string& bytes, pmsm::MeasurementFormat format, ScratchFile& file) {
    // libhdf5 keeps state from one file to the next (identifiers, free lists, caches), which a damaged
    // file can leave inconsistent: then a later, harmless input faults, and the finding names the
    // wrong input. The program reads each file in a child process of its own, which starts clean, so
    // the fuzzer closes the library after each input that reached it (it reopens on its next call).
    struct CloseLibhdf5 {
        bool used;
        ~CloseLibhdf5() {
            if (used) H5close();
        }
    } close_afterwards{format != pmsm::MeasurementFormat::Mat5};
    // In this process: the fuzzer looks for the faults a child process would turn into refusals.
    pmsm::read_binary_measurement(file.holding(bytes), format, {}, pmsm::Isolation::in_process);
}

ScratchFile& mat_file() {
    static ScratchFile file(".mat");
    return file;
}

ScratchFile& hdf5_file() {
    static ScratchFile file(".h5");
    return file;
}

void parse_mat5_file(const std::string& bytes) { parse_binary_file(bytes, pmsm::MeasurementFormat::Mat5, mat_file()); }
void parse_mat73_file(const std::string& bytes) { parse_binary_file(bytes, pmsm::MeasurementFormat::Mat73, mat_file()); }
void parse_hdf5_file(const std::string& bytes) { parse_binary_file(bytes, pmsm::MeasurementFormat::Hdf5, hdf5_file()); }

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

int load_hdf5_reader() {
    pmsm::hdf5_reader();
    return 0;
}

int fuzz_one_input(std::string_view name, const std::uint8_t* data, std::size_t size) {
    static const InputFormat& format = input_format(name);
    accept_or_refuse(format, std::string(reinterpret_cast<const char*>(data), size));
    return 0;
}

}  // namespace mhb::fuzz

#include "tests/fuzz/input_formats.hpp"

#include <array>
#include <stdexcept>

#include "framework/experiment_config.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/model/model_spec.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"

namespace mhb::fuzz {
namespace {

void parse_experiment_text(const std::string& text) { parse_experiment(text, "fuzz.toml", PluginLoading::record_only); }

// Parsing only: a valid profile may ask for minutes of simulation, which would read as a hang.
// The base directory is never touched while parsing (the plant reads a flux map when it is built).
void parse_profile_text(const std::string& text) { pmsm::parse_simulation_profile(text, "fuzz.toml", "."); }

void parse_measurement_text(const std::string& text) { pmsm::parse_measurement(text, "fuzz.csv"); }

// A typical magnet flux; the parser only checks the map, the value scales it later.
void parse_flux_map_text(const std::string& text) { pmsm::FluxMap::parse(text, "fuzz.csv", 0.1); }

void parse_model_spec_text(const std::string& text) { pmsm::parse_model_spec(text); }

constexpr std::array formats{
    InputFormat{"experiment", parse_experiment_text},
    InputFormat{"simulation_profile", parse_profile_text},
    InputFormat{"measurement", parse_measurement_text},
    InputFormat{"flux_map", parse_flux_map_text},
    InputFormat{"model_spec", parse_model_spec_text},
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

#pragma once
// Simulated drive data with hidden effects for the fit and diagnosis tests, made once per process
// and shared between test cases (each simulation is a few hundred milliseconds).
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/mhbench_cli.hpp"

namespace mhb::pmsm::testing {

using mhb::testing::run_mhbench;

struct HiddenEffect {
    std::string name;
    std::map<std::string, ParameterValue> values;
};

// The true base parameters of the Table 1 motor (at 20 °C).
inline const Eigen::Vector4d table1_truth(46.0, 0.02025, 0.02025, 0.04375);

inline std::filesystem::path profile_path(const std::string& name) {
    return std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / name;
}

// The profile `name` from experiments/pmsm/ with `effects` switched on (replacing the profile's own
// effects unless `keep_profile_effects`), simulated once and cached under `key`.
inline const Measurement& simulated(const std::string& key, const std::string& name, const std::vector<HiddenEffect>& effects,
                                    bool keep_profile_effects = false) {
    static std::map<std::string, Measurement> cache;
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    auto spec = read_simulation_profile(profile_path(name));
    if (!keep_profile_effects) spec.effects.clear();
    for (const auto& e : effects) spec.effects.push_back(make_effect(e.name, e.values));
    auto result = simulate(spec);
    result.data.source = key;
    return cache.emplace(key, std::move(result.data)).first->second;
}

// The diagnosis profile (docs/tutorial-missing-physics.md) with hidden effects.
inline const Measurement& diagnosis_data(const std::vector<HiddenEffect>& effects) {
    std::string key = "diagnosis";
    for (const auto& e : effects) key += "+" + e.name;
    return simulated(key, "diagnosis_profile.toml", effects);
}

// The device study's drive (device_diagnosis_profile.toml: nine operating points at +-10 and +-45
// r/min) without noise, its plant changed by `change`, fitted with `model`: the base parameters'
// relative errors against the motor's (small-current) values.
template <class Change>
Eigen::Vector4d noise_free_device_errors(const std::string& model, Change change) {
    auto drive = read_simulation_profile(profile_path("device_diagnosis_profile.toml"));
    drive.noise = SensorNoise{};
    change(*drive.device);
    const ModelFit fit = fit_model(simulate(drive).data, parse_model_spec(model), FitOptions{});
    const Eigen::Vector4d truth{drive.motor.rs, drive.motor.ld, drive.motor.lq, drive.motor.psi_f};
    return fit.values.head<4>().cwiseQuotient(truth).array() - 1.0;
}

// A fit of `model` whose base parameters are `base` and its effects' parameters zero: enough for what
// an effect states from the base values alone (Effect::unseen_bias).
inline ModelFit fit_at(const std::string& model, const Eigen::Vector4d& base) {
    ModelFit fit;
    fit.spec = parse_model_spec(model);
    Eigen::Index count = 4;
    for (const auto& term : fit.spec.effects) count += static_cast<Eigen::Index>(make_effect(term.name)->parameter_names().size());
    fit.values = Eigen::VectorXd::Zero(count);
    fit.values.head<4>() = base;
    return fit;
}

}  // namespace mhb::pmsm::testing

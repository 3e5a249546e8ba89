#pragma once
// What `mhbench fit` prints and writes, and the pieces of it that the diagnosis report repeats for
// each model it shows: console text, and JSON for programs (the contract in docs/effects.md).
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/diagnosis/shared_noise.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"

namespace mhb::pmsm {

// {"model", "data", "samples", "method", "rms": {"u_d", "u_q", "total"}, "parameters": {name: {"value",
// "ci95", "standard_error", "unit", "fixed", "range", "at_bound"}}, "segments": [...]}; intervals the
// data do not determine are null.
nlohmann::ordered_json fit_json(const ModelFit& fit);
std::string fit_text(const ModelFit& fit, const Measurement& data);

// The base parameters of `fit` corrected for a stated control period's sample and hold: a paragraph
// giving the bias and the corrected values with their intervals (each moved by the bias), and
// {"control_period", "carrier_frequency", "dc_voltage" (with the carrier), "bias": {name: relative}, "corrected": {name: {"value", "ci95"}}}.
std::string sample_and_hold_text(const ModelFit& fit, const SampleAndHold& held);
nlohmann::ordered_json sample_and_hold_json(const ModelFit& fit, const SampleAndHold& held);

// The base parameters of `fit` corrected for the noise its data's current and voltage share (and,
// with `held`, for the sample and hold too): a paragraph giving the bias and the corrected values
// with their intervals (moved by the biases, widened by the shared noise's standard error), and
// {"windows", "relevant", "bias": {name: relative}, "standard_error": {name: relative},
// "corrected": {name: {"value", "ci95"}}}, "corrected" for both biases when `held` is given.
std::string shared_noise_text(const ModelFit& fit, const SharedNoise& shared, const SampleAndHold* held);
nlohmann::ordered_json shared_noise_json(const ModelFit& fit, const SharedNoise& shared, const SampleAndHold* held);

// What `mhbench fit` (and Python's fit) states beside the fitted values: the sample and hold of a
// stated control period (none when `timing` states none), the noise the current and voltage share
// (none where it cannot be measured).
struct FitCorrections {
    std::optional<SampleAndHold> held;
    std::optional<SharedNoise> shared;
};
FitCorrections fit_corrections(const Measurement& data, const ModelFit& fit, const DriveTiming& timing);
// Their paragraphs, the shared noise's only where it is relevant (SharedNoise::relevant), and
// {"sample_and_hold", "shared_noise"} as far as each is there, for fit_json's object.
std::string corrections_text(const ModelFit& fit, const FitCorrections& corrections);
nlohmann::ordered_json corrections_json(const ModelFit& fit, const FitCorrections& corrections);

// The fields fit_json is made of.
nlohmann::ordered_json finite_or_null(double v);
nlohmann::ordered_json rms_json(const AxisRms& r);
nlohmann::ordered_json parameters_json(const ModelFit& fit);
nlohmann::ordered_json segments_json(const std::vector<SegmentResidual>& segments);

// Numbers as fit_text and the report tables show them: a value (— when not finite), a parameter's
// 95 % interval in words, volts as millivolts.
std::string value_text(double v);
std::string interval_text(const ModelFit& fit, Eigen::Index j);
std::string mv(double volts);

}  // namespace mhb::pmsm

#pragma once
// What `mhbench fit` prints and writes, and the pieces of it that the diagnosis report repeats for
// each model it shows: console text, and JSON for programs (the contract in docs/effects.md).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "problems/pmsm/data/measurement.hpp"
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

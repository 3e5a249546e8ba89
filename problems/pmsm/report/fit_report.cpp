#include "problems/pmsm/report/fit_report.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace mhb::pmsm {

using json = nlohmann::ordered_json;

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json rms_json(const AxisRms& r) { return {{"u_d", r.d}, {"u_q", r.q}, {"total", r.total}}; }

json parameters_json(const ModelFit& fit) {
    json p = json::object();
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        json e;
        e["value"] = fit.values[k];
        if (fit.free[j]) {
            e["ci95"] = std::isfinite(fit.lower[k]) ? json::array({fit.lower[k], fit.upper[k]}) : json(nullptr);
            e["standard_error"] = finite_or_null(fit.standard_error[k]);
        }
        e["unit"] = fit.units[j];
        e["fixed"] = !fit.free[j];
        e["range"] = json::array({fit.range_lower[k], fit.range_upper[k]});
        if (fit.free[j] && j >= 4) e["at_bound"] = fit.at_bound(k);
        if (fit.beyond_range(k)) e["beyond_range"] = true;
        if (fit.spread_widened(k)) e["interval"] = "segment jackknife";
        p[fit.names[j]] = e;
    }
    return p;
}

json segments_json(const std::vector<SegmentResidual>& segments) {
    json out = json::array();
    for (const auto& s : segments)
        out.push_back({{"label", s.label}, {"rows", s.rows}, {"rms", rms_json(s.rms)}, {"mean_residual", {{"u_d", s.mean[0]}, {"u_q", s.mean[1]}}}});
    return out;
}

std::string value_text(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string("—"); }

std::string interval_text(const ModelFit& fit, Eigen::Index j) {
    if (!fit.free[static_cast<std::size_t>(j)]) return "fixed";
    if (!std::isfinite(fit.lower[j])) return "not determined by the data";
    return fmt::format("[{:.6g}, {:.6g}]", fit.lower[j], fit.upper[j]);
}

std::string mv(double volts) { return fmt::format("{:.2f}", 1e3 * volts); }

json fit_json(const ModelFit& fit) {
    json out;
    out["model"] = fit.spec.text();
    out["samples"] = fit.samples;
    out["method"] = fit.method;
    out["rms"] = rms_json(fit.rms);
    out["parameters"] = parameters_json(fit);
    out["uncertainty"] = {{"method", to_string(fit.uncertainty.method)},
                          {"axis_rho", {{"u_d", fit.uncertainty.axis_rho.size() ? fit.uncertainty.axis_rho[0] : 0.0},
                                        {"u_q", fit.uncertainty.axis_rho.size() > 1 ? fit.uncertainty.axis_rho[1] : 0.0}}}};
    if (const auto biases = fit.unseen_biases(); !biases.empty())
        for (const auto& bias : biases) out["uncertainty"]["unseen_biases"].push_back(bias.text);
    out["segments"] = segments_json(fit.segments);
    return out;
}

std::string fit_text(const ModelFit& fit, const Measurement& data) {
    std::string t = fmt::format("data: {} ({} samples{})\n", data.source, data.size(),
                                data.has_segments() ? fmt::format(" in {} segments", data.segment_labels.size()) : std::string());
    t += current_loop_text(data.current_loop_bandwidth, data.current_loop_delay);
    t += fmt::format("model: {}\nfitted by {}\n\n", fit.spec.text(), fit.method);
    t += fmt::format("{:<28} {:>14} {:>36}  {}\n", "parameter", "value", "95 % interval", "unit");
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        t += fmt::format("{:<28} {:>14} {:>36}  {}{}{}\n", fit.names[j], value_text(fit.values[k]), interval_text(fit, k), fit.units[j],
                         fit.at_bound(k) ? "  (at a bound of its plausible range)" : fit.beyond_range(k) ? "  (beyond its plausible range for this log)" : "",
                         fit.spread_widened(k) ? "  (*)" : "");
    }
    if (std::find(fit.segment_spread.begin(), fit.segment_spread.end(), true) != fit.segment_spread.end())
        t += "(*) interval widened to the spread over segments: the segments pull this parameter, or one it trades against, apart by more "
             "than the residual's noise would: the model misses structure between them, or noise in the logged current moves each "
             "segment its own way (`diagnose` tells which; docs/diagnosis.md, sections 4 and 7)\n";
    for (const auto& bias : fit.unseen_biases()) t += "note: " + bias.text + "\n";
    t += fmt::format("\nresidual rms: u_d {:.4g} V, u_q {:.4g} V, combined {:.4g} V\n", fit.rms.d, fit.rms.q, fit.rms.total);
    if (fit.segments.size() > 1) {
        t += fmt::format("\n{:<28} {:>6} {:>11} {:>11} {:>11}\n", "segment", "rows", "u_d (V)", "u_q (V)", "total (V)");
        for (const auto& s : fit.segments)
            t += fmt::format("{:<28} {:>6} {:>11.4g} {:>11.4g} {:>11.4g}\n", s.label, s.rows, s.rms.d, s.rms.q, s.rms.total);
    }
    return t;
}

std::string sample_and_hold_text(const ModelFit& fit, const SampleAndHold& held) {
    if (!held.bias.allFinite())
        return fmt::format("\nsample and hold of the stated control period ({}): not corrected, the fitted Rs, Ld or Lq is not positive\n",
                           timing_text(held.timing));
    std::string t = fmt::format(
        "\nsample and hold of the stated control period ({}): a drive that samples the currents once a period and holds the voltage it "
        "computes over the next{} makes the continuous model read {} off the machine (docs/diagnosis.md); corrected:\n",
        timing_text(held.timing), held.timing.carrier() ? ", switching it by the carrier," : "",
        fmt::join(shift_texts(held, fit.names, fit.values), ", "));
    for (Eigen::Index j = 0; j < 4; ++j) {
        const auto k = static_cast<std::size_t>(j);
        const std::string interval = !fit.free[k] ? "fixed"
                                     : std::isfinite(fit.lower[j])
                                         ? fmt::format("[{:.6g}, {:.6g}]", fit.lower[j] - held.bias[j], fit.upper[j] - held.bias[j])
                                         : "not determined by the data";
        t += fmt::format("{:<28} {:>14} {:>36}  {}\n", fit.names[k], value_text(fit.values[j] - held.bias[j]), interval, fit.units[k]);
    }
    return t;
}

json sample_and_hold_json(const ModelFit& fit, const SampleAndHold& held) {
    json out;
    out["control_period"] = held.timing.control_period;
    if (held.timing.carrier()) {
        out["carrier_frequency"] = held.timing.carrier_frequency;
        out["dc_voltage"] = held.timing.dc_voltage;
    }
    json bias = json::object(), corrected = json::object();
    for (Eigen::Index j = 0; j < 4; ++j) {
        const auto& name = fit.names[static_cast<std::size_t>(j)];
        const double value = fit.values[j] - held.bias[j];
        bias[name] = held.bias[j] / value;
        corrected[name] = {{"value", value},
                           {"ci95", fit.free[static_cast<std::size_t>(j)] && std::isfinite(fit.lower[j])
                                        ? json::array({fit.lower[j] - held.bias[j], fit.upper[j] - held.bias[j]})
                                        : json(nullptr)}};
    }
    out["bias"] = bias;
    out["corrected"] = corrected;
    return out;
}

namespace {

double held_bias(const SampleAndHold* held, Eigen::Index j) { return held && held->bias.allFinite() ? held->bias[j] : 0.0; }

}  // namespace

std::string shared_noise_text(const ModelFit& fit, const SharedNoise& shared, const SampleAndHold* held) {
    const std::vector<std::string> shifts = shared.shift_texts(fit);
    std::string t = fmt::format(
        "\nnoise the current and the voltage share (a current loop answers the current sensors' noise within its control period, and a "
        "noisy current enters R i, omega L i and the effects' laws): measured in {} steady window{}, it makes the model read {} off the "
        "machine (docs/diagnosis.md); corrected{}:\n",
        shared.windows, shared.windows == 1 ? "" : "s", fmt::join(shifts, ", "),
        held && held->bias.allFinite() ? " for it and for the sample and hold above" : "");
    for (Eigen::Index j = 0; j < 4; ++j) {
        const auto k = static_cast<std::size_t>(j);
        const auto [lo, hi] = shared.corrected_interval(fit, j, held_bias(held, j));
        const std::string interval = !fit.free[k] ? "fixed" : std::isfinite(lo) && std::isfinite(hi) ? fmt::format("[{:.6g}, {:.6g}]", lo, hi)
                                                                                                       : "not determined by the data";
        t += fmt::format("{:<28} {:>14} {:>36}  {}\n", fit.names[k], value_text(fit.values[j] - shared.bias[j] - held_bias(held, j)), interval,
                         fit.units[k]);
    }
    return t;
}

json shared_noise_json(const ModelFit& fit, const SharedNoise& shared, const SampleAndHold* held) {
    json out;
    out["windows"] = shared.windows;
    out["relevant"] = shared.relevant();
    json bias = json::object(), error = json::object(), corrected = json::object();
    for (Eigen::Index j = 0; j < 4; ++j) {
        const auto& name = fit.names[static_cast<std::size_t>(j)];
        const double value = fit.values[j] - shared.bias[j] - held_bias(held, j);
        bias[name] = shared.bias[j] / value;
        error[name] = finite_or_null(shared.standard_error[j] / value);
        const auto [lo, hi] = shared.corrected_interval(fit, j, held_bias(held, j));
        corrected[name] = {{"value", value},
                           {"ci95", fit.free[static_cast<std::size_t>(j)] && std::isfinite(lo) && std::isfinite(hi) ? json::array({lo, hi})
                                                                                                                    : json(nullptr)}};
    }
    out["bias"] = bias;
    out["standard_error"] = error;
    out["corrected"] = corrected;
    return out;
}

FitCorrections fit_corrections(const Measurement& data, const ModelFit& fit, const DriveTiming& timing) {
    FitCorrections out;
    if (timing.control_period > 0.0) out.held = SampleAndHold{timing, sample_and_hold_bias(data, fit.values.head<4>(), timing)};
    out.shared = shared_noise_bias(data, fit);
    return out;
}

std::string corrections_text(const ModelFit& fit, const FitCorrections& corrections) {
    std::string t;
    if (corrections.held) t += sample_and_hold_text(fit, *corrections.held);
    if (corrections.shared && corrections.shared->relevant())
        t += shared_noise_text(fit, *corrections.shared, corrections.held ? &*corrections.held : nullptr);
    return t;
}

json corrections_json(const ModelFit& fit, const FitCorrections& corrections) {
    json out = json::object();
    if (corrections.held) out["sample_and_hold"] = sample_and_hold_json(fit, *corrections.held);
    if (corrections.shared) out["shared_noise"] = shared_noise_json(fit, *corrections.shared, corrections.held ? &*corrections.held : nullptr);
    return out;
}

}  // namespace mhb::pmsm

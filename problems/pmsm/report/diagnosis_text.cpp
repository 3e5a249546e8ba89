#include "problems/pmsm/report/diagnosis_report.hpp"
#include "problems/pmsm/diagnosis/noise.hpp"

#include <cmath>

#include <fmt/format.h>

namespace mhb::pmsm {
namespace {

std::string path_text(const Diagnosis& d) {
    std::string t = "search over sets of effects:\n";
    t += fmt::format("  {:<52} {:>10} {:>11} {:>10}  {}\n", "model", "rms (V)", "dBIC", "explained", "plausible");
    for (const auto& step : d.path)
        t += fmt::format("  {:<52} {:>10.4g} {:>11} {:>9.0f}%  {}{}\n", (step.change().empty() ? "" : step.change() + " -> ") + step.fit.spec.text(),
                         step.fit.rms.total, step.change().empty() ? std::string("—") : fmt::format("{:.1f}", step.delta_bic), 100.0 * step.explained,
                         step.plausible ? "yes" : "no", step.at_noise_floor ? ", at the noise floor" : "");
    t += fmt::format("recommended model: {}{}\n", d.recommended.text(), d.incomplete ? " (and something else is missing)" : "");
    return t;
}

}  // namespace

std::string noise_from_data_text(const NoiseEstimate& n) {
    std::string t = fmt::format("noise measured from the data: u_d {:.3g} V (lag-one correlation {:.2f}), u_q {:.3g} V ({:.2f}); from {}",
                                n.window.sigma[0], n.window.correlation[0], n.window.sigma[1], n.window.correlation[1], window_noise_method(n.window));
    const bool d = n.from_windows[0], q = n.from_windows[1];
    if (d || q)
        t += fmt::format("; the evidence is measured in it on {}: the residual's noise exceeds it more than {}-fold, so it holds structure",
                         d && q ? "both axes" : d ? "u_d" : "u_q", residual_structure_ratio);
    else
        t += "; the evidence is measured in the residual's noise, within " + fmt::format("{}", residual_structure_ratio) + "-fold of it";
    return t;
}

std::string diagnosis_text(const Diagnosis& d) {
    std::string t = fmt::format("data: {} ({} samples in {} segments)\n{}model: {}: residual rms u_d {:.4g} V, u_q {:.4g} V, combined {:.4g} V\n\n",
                                d.source, d.samples, d.segments.size(), current_loop_text(d.current_loop_bandwidth, d.current_loop_delay),
                                d.model.spec.text(), d.model.rms.d, d.model.rms.q, d.model.rms.total);
    t += fmt::format("{:<4} {:<16} {:<17} {:>12} {:>11} {:>12} {}\n", "rank", "added effect", "verdict", "rms after (V)", "dBIC", "LOSO (V)",
                     "identifiability");
    for (std::size_t k = 0; k < d.candidates.size(); ++k) {
        const auto& c = d.candidates[k];
        t += fmt::format("{:<4} {:<16} {:<17} {:>12.4g} {:>11.1f} {:>12} {}\n", k + 1, c.effect, to_string(c.verdict), c.fit.rms.total, c.delta_bic,
                         c.loso_rms ? fmt::format("{:.4g}", *c.loso_rms) : std::string("—"), to_string(c.identifiability));
    }
    if (d.noise.dispersion > 1.0)
        t += fmt::format("(dBIC above divided by {:.3g}, the overdispersion of the best single fit's segment means: structure no single "
                         "effect explains is not counted as evidence; the search over sets below does not divide, docs/diagnosis.md, "
                         "section 1)\n",
                         d.noise.dispersion);
    t += "\n" + path_text(d) + "\n";
    for (const auto& f : d.findings) t += "- " + f + "\n";
    if (!d.lack_of_fit.mechanical_angle.empty()) t += "mechanical orders (k/p of the electrical frequency): " + d.lack_of_fit.mechanical_angle + "\n";
    t += noise_from_data_text(d.noise) + "\n";
    if (!d.detection_limits.empty()) {
        t += "\ndetection limits of this log: the smallest size at which each effect left out would be found (in about half of such logs; "
             "marked *: set by the voltage it must change rather than by the evidence, docs/diagnosis.md, section 5)\n";
        for (const auto& l : d.detection_limits) {
            const std::string size = std::isfinite(l.limit) ? fmt::format("{:.3g} {}{}", l.limit, l.unit, l.set_by_relevant_size ? " *" : "")
                                                            : std::string("no size shows in this log");
            t += l.typical != 0.0 ? fmt::format("  {:<30} {:<36} (default {:.3g})\n", l.parameter, size, l.typical)
                                  : fmt::format("  {:<30} {}\n", l.parameter, size);
        }
    }
    return t;
}

}  // namespace mhb::pmsm

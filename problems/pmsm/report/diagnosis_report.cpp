#include "problems/pmsm/report/diagnosis_report.hpp"

#include "problems/pmsm/report/diagnosis_plots.hpp"
#include "problems/pmsm/report/fit_report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "framework/file_output.hpp"
#include "framework/html_report.hpp"
#include "framework/input_error.hpp"
#include "framework/plots.hpp"
#include "framework/provenance.hpp"
#include "framework/shell_word.hpp"

namespace mhb::pmsm {
namespace fs = std::filesystem;
namespace {

using json = nlohmann::ordered_json;

// ---- markdown ----

Table parameter_table(const ModelFit& fit) {
    Table table(fit.spec.text() + ": parameters", {"parameter", "value", "95 % interval", "unit", "plausible range"});
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        table.add_row({fit.names[j], value_text(fit.values[k]), interval_text(fit, k), fit.units[j],
                       fmt::format("[{:g}, {:g}]{}", fit.range_lower[k], fit.range_upper[k], fit.at_bound(k) ? " (at a bound)" : "")});
    }
    return table;
}

// A plot the report shows, when gnuplot drew it (`file` empty: it did not).
void add_image(Document& doc, const std::string& file, const std::string& caption) {
    if (!file.empty()) doc.add(Image{file, caption});
}

// Where the segments of a log without a segment column came from, so that the windows can be checked
// against the log before the diagnosis on them is trusted.
void add_found_operating_points(Document& doc, const FoundOperatingPoints& found, const DiagnosisPlots& png) {
    const auto& p = found.points;
    doc.add(Heading{2, "Operating points found in the log"});
    doc.add(Paragraph{fmt::format("The log has no segment column: its steady windows, found automatically, are the segments below (steady1 to "
                                  "steady{}), and the rows between them are dropped as transient (docs/diagnosis.md, \"Operating points found in a "
                                  "raw log\"; `--steady-bandwidth`, `--steady-min-rows`, `--steady-false-alarm` set the test).",
                                  p.windows.size())});
    add_image(doc, png.operating_points,
              fmt::format("{} steady windows (shaded) found by the moving-sum (MOSUM) change-point test on {} with a bandwidth of {} rows a side "
                          "(false-alarm probability {:g}, windows of at least {} rows); {} of {} rows dropped as transient (white)",
                          p.windows.size(), fmt::join(p.channels, ", "), p.bandwidth, p.false_alarm, p.min_rows, p.transient_rows, p.rows));
}

// The findings, the search over sets of effects and the recommendation, with the commands to run next.
void add_summary(Document& doc, const Diagnosis& d, const DiagnosisPlots& png, const std::string& data_path, const std::string& data_options,
                 const FoundOperatingPoints* found) {
    const auto& m = d.model;
    doc.add(Heading{1, fmt::format("Diagnosis of `{}` on `{}`", m.spec.text(), data_path)});
    doc.add(Paragraph{fmt::format("{} samples in {} segments; optional columns: {}.", d.samples, d.segments.size(),
                                  d.columns.empty() ? std::string("none") : fmt::format("{}", fmt::join(d.columns, ", ")))});
    if (found) add_found_operating_points(doc, *found, png);
    doc.add(Heading{2, "What the diagnosis says"});
    doc.add(BulletList{d.findings});
    doc.add(Heading{2, "The search over sets of effects"});
    doc.add(Paragraph{"Forward selection with backward pruning: each step adds the library effect with the strongest evidence that the design can "
                      "identify and that predicts held-out segments; plausibility is judged on the whole set, so a step may pass through values "
                      "that one effect takes alone while another is still missing (docs/effects.md, \"Several effects at once\"). dBIC of each "
                      "step against the one before, with the final noise estimate; explained: share of the excess residual of `" + m.spec.text() +
                      "` over the noise floor."});
    Table path("the search over sets of effects",
               {"step", "model", Column("rms", "mV"), "dBIC", "explained", "plausible", "at the noise floor"});
    for (std::size_t k = 0; k < d.path.size(); ++k) {
        const auto& step = d.path[k];
        path.add_row({step.change().empty() ? std::string("start") : step.change(), "`" + step.fit.spec.text() + "`", mv(step.fit.rms.total),
                      k == 0 ? std::string("—") : fmt::format("{:.1f}", step.delta_bic), fmt::format("{:.0f} %", 100.0 * step.explained),
                      step.plausible ? "yes" : "no: " + step.implausible.front(), step.at_noise_floor ? "yes" : "no"});
    }
    doc.add(std::move(path));
    doc.add(Paragraph{fmt::format("**Recommended model: `{}`**{}", d.recommended.text(),
                                  d.recommended.text() == m.spec.text()
                                      ? (!d.not_in_library ? " (no missing effect is recommended: see the findings)"
                                         : d.not_in_library_by_harmonics() ? " (what it leaves is within the noise floor's tolerance, but holds a harmonic no library law makes: see the findings)"
                                                                         : " (no set of library effects reaches the noise floor with plausible values)")
                                      : (d.incomplete ? " (and something else is missing: see the findings)" : ""))});
    add_image(doc, png.path, "residual after each step of the search");
    if (d.recommended.text() != m.spec.text() || !d.tie.empty()) {
        const std::string next = shell_word(d.recommended.text() != m.spec.text() ? d.recommended.text() : m.spec.with(d.tie.front()).text());
        doc.add(Paragraph{"Next step:"});
        const std::string data_word = shell_word(data_path);
        doc.add(Preformatted{fmt::format("mhbench fit --data {}{} --model {}\nmhbench diagnose --data {}{} --model {} --report <dir>", data_word,
                                         data_options, next, data_word, data_options, next)});
    }
}

void add_fitted_model(Document& doc, const Diagnosis& d) {
    const auto& m = d.model;
    doc.add(Heading{2, "The fitted model"});
    doc.add(Paragraph{fmt::format("`{}`, fitted by {}. Residual rms: u_d {} mV, u_q {} mV, combined {} mV.", m.spec.text(), m.method, mv(m.rms.d),
                                  mv(m.rms.q), mv(m.rms.total))});
    doc.add(parameter_table(m));
    doc.add(Paragraph{"Intervals: 95 %, from the Jacobian with AR(1)-prewhitened Newey-West covariance within segments (docs/pmsm.md, \"Uncertainty\")."});
    if (d.build_up.size() > 1) {
        doc.add(Paragraph{"Error before and after the effects:"});
        Table steps("error before and after the effects", {"model", Column("u_d", "mV"), Column("u_q", "mV"), Column("combined", "mV")});
        for (const auto& s : d.build_up) steps.add_row({"`" + s.spec.text() + "`", mv(s.rms.d), mv(s.rms.q), mv(s.rms.total)});
        doc.add(std::move(steps));
    }
}

// The noise floor, the residual per segment and the plots against time, angle and operating conditions.
void add_where_it_fails(Document& doc, const Diagnosis& d, const Measurement& data, const DiagnosisPlots& png) {
    const auto& m = d.model;
    doc.add(Heading{2, "Where it fails"});
    doc.add(Paragraph{fmt::format("Noise floor: {} mV on u_d, {} mV on u_q per sample (within-segment scatter of the best model tried, `{}`); a segment mean "
                                  "of n samples has a standard error of {} mV / sqrt(n) on u_d and {} mV / sqrt(n) on u_q (serial correlation included: "
                                  "{:.0f} effective samples of {}).",
                                  mv(d.noise.sigma[0]), mv(d.noise.sigma[1]), d.noise.model, mv(d.noise.long_run[0]), mv(d.noise.long_run[1]),
                                  d.noise.effective_samples, 2 * d.samples)});
    const bool tw = data.temp_winding.has_value(), tm = data.temp_magnet.has_value(), base_shown = d.build_up.size() > 1;
    std::vector<Column> segment_columns{"segment", Column("omega_e", "rad/s"), Column("i_d", "A"), Column("i_q", "A")};
    if (tw) segment_columns.emplace_back("T_w", "°C");
    if (tm) segment_columns.emplace_back("T_m", "°C");
    if (base_shown) segment_columns.emplace_back("rms base", "mV");
    for (const char* name : {"rms", "mean u_d ± SE", "mean u_q ± SE"}) segment_columns.emplace_back(name, "mV");
    const ModelFit* recommended = recommended_to_show(d);
    if (recommended) segment_columns.emplace_back("rms recommended", "mV");
    Table segments("residual per segment", std::move(segment_columns));
    for (std::size_t k = 0; k < d.segments.size(); ++k) {
        const auto& s = d.segments[k];
        std::vector<Cell> row{s.label, fmt::format("{:.2f}", s.omega), fmt::format("{:.4f}", s.i_d), fmt::format("{:.4f}", s.i_q)};
        if (tw) row.emplace_back(fmt::format("{:.1f}", *s.temp_winding));
        if (tm) row.emplace_back(fmt::format("{:.1f}", *s.temp_magnet));
        if (base_shown) row.emplace_back(mv(s.before.rms.total));
        row.emplace_back(mv(s.model.rms.total));
        row.emplace_back(mv(s.model.mean[0]) + " ± " + mv(s.mean_standard_error[0]));
        row.emplace_back(mv(s.model.mean[1]) + " ± " + mv(s.mean_standard_error[1]));
        if (recommended) row.emplace_back(mv(recommended->segments[k].rms.total));
        segments.add_row(std::move(row));
    }
    doc.add(std::move(segments));
    if (recommended)
        doc.add(Paragraph{fmt::format("\"rms recommended\" and the green marks in the plots below: the residual of the recommended model, `{}` ({} mV "
                                      "combined), beside the model diagnosed.",
                                      recommended->spec.text(), mv(recommended->rms.total))});
    const auto& l = d.lack_of_fit;
    if (l.means_available)
        doc.add(Paragraph{fmt::format("Segment means against the noise: chi-square {:.1f} on {} degrees of freedom, p = {:.2g}{}.", l.statistic, l.dof,
                                      l.p_value, l.p_value < 1e-3 ? " — the model misses something that changes between operating points" : "")});
    else
        doc.add(Paragraph{fmt::format("The segment means cannot test the model: {} equations for {} free parameters.", d.mean_equations, m.free_count())});
    if (!l.harmonics.empty()) {
        doc.add(Paragraph{"Harmonics of the electrical angle in the residual (amplitudes in mV; noise: standard error of one amplitude):"});
        Table harmonics("harmonics of the electrical angle in the residual", {"order", "u_d", "u_q", "noise", "p"});
        for (const auto& h : l.harmonics)
            harmonics.add_row({std::to_string(h.order), mv(h.amplitude[0]), mv(h.amplitude[1]), mv(h.standard_error), fmt::format("{:.2g}", h.p_value)});
        doc.add(std::move(harmonics));
    }
    if (!l.mechanical_angle.empty()) {
        doc.add(Paragraph{"Harmonics at mechanical orders (k/p of the electrical frequency) in the residual: " + l.mechanical_angle + "."});
        if (!l.mechanical_harmonics.empty()) {
            Table mechanical("harmonics at mechanical orders in the residual",
                             {"order (per turn)", "of the electrical frequency", "u_d", "u_q", "noise", "phase on u_q (rad)", "p", "segments"});
            for (const auto& h : l.mechanical_harmonics)
                mechanical.add_row({std::to_string(h.order), fmt::format("{}/{}", h.order, h.pole_pairs), mv(h.amplitude[0]), mv(h.amplitude[1]),
                                    mv(h.standard_error), h.phase ? fmt::format("{:.2f}", (*h.phase)[1]) : std::string("per segment"),
                                    fmt::format("{:.2g}", h.p_value), std::to_string(h.segments)});
            doc.add(std::move(mechanical));
        }
    }
    add_image(doc, png.rms, "residual rms per segment");
    add_image(doc, png.time, "residual against time");
    add_image(doc, png.angle, "residual against the electrical angle");
    add_image(doc, png.speed, "segment-mean residual against speed");
    add_image(doc, png.current, "segment-mean residual against current");
    add_image(doc, png.temperature, "segment-mean residual against temperature");
}

// Each free parameter refitted alone per segment, and the drifts of these values.
void add_apparent_parameters(Document& doc, const Diagnosis& d, const DiagnosisPlots& png) {
    doc.add(Heading{3, "Parameters refitted per segment"});
    doc.add(Paragraph{"Each free parameter refitted alone on one segment, all others at the global fit: the value that segment asks for (— where the "
                      "segment does not move the prediction with that parameter). A drift with temperature, current or speed names what the model lacks."});
    std::vector<Column> apparent_columns{"segment"};
    apparent_columns.insert(apparent_columns.end(), d.apparent_names.begin(), d.apparent_names.end());
    Table apparent("parameters refitted per segment", std::move(apparent_columns));
    for (const auto& s : d.segments) {
        std::vector<Cell> row{s.label};
        for (const auto& a : s.apparent) row.emplace_back(a.determined ? fmt::format("{:.5g} ± {:.2g}", a.value, a.standard_error) : std::string("—"));
        apparent.add_row(std::move(row));
    }
    doc.add(std::move(apparent));
    if (d.drifts.empty()) doc.add(Paragraph{"No apparent parameter varies between segments beyond its noise."});
    // Added even when empty: report.md has always had a blank line more after the sentence above.
    BulletList drifts;
    for (const auto& x : d.drifts)
        drifts.items.push_back(x.variable.empty()
                                   ? fmt::format("apparent {} varies between segments beyond its noise, following none of temperature, current or speed alone.",
                                                 x.parameter)
                                   : fmt::format("apparent {} follows {} (r = {:.2f}, slope {:.4g} per unit of {}).", x.parameter, x.variable, x.correlation,
                                                 x.slope, x.variable));
    doc.add(std::move(drifts));
    add_image(doc, png.apparent, "parameters refitted per segment");
}

void add_candidates(Document& doc, const Diagnosis& d, const DiagnosisPlots& png) {
    const auto& m = d.model;
    doc.add(Heading{2, "Which effect is missing"});
    doc.add(Paragraph{fmt::format("Each library effect whose columns the data have was added to `{}` and fitted. Evidence: the residual after it; "
                                  "dBIC = -LR + k ln(n_eff), with LR the fall in squared residual divided by the long-run noise variance"
                                  "{} and n_eff = {:.0f} effective samples (below -10: very strong, above -2: none); LOSO, the rms error predicting "
                                  "each segment from a fit to the others, and in how many segments it beats `{}`{}; plausibility of the refitted values; "
                                  "identifiability on the design.",
                                  m.spec.text(),
                                  d.noise.dispersion > 1.0 ? fmt::format(" and by the lack of fit of the best model, {:.3g} (so structure no candidate "
                                                                         "explains does not count as evidence)",
                                                                         d.noise.dispersion)
                                                           : std::string(),
                                  d.noise.effective_samples, m.spec.text(),
                                  d.model_loso_rms ? fmt::format(" (its own LOSO: {} mV)", mv(*d.model_loso_rms))
                                                   : std::string(" (not available: fewer than 3 segments)"))});
    Table candidates("candidate effects", {"rank", "added effect", "verdict", Column("rms after", "mV"), "dBIC", "LOSO (mV), segments better", "plausible",
                                           "identifiability (unique part)"});
    for (std::size_t k = 0; k < d.candidates.size(); ++k) {
        const auto& c = d.candidates[k];
        candidates.add_row({std::to_string(k + 1), c.effect, fmt::format("**{}**", to_string(c.verdict)), mv(c.fit.rms.total), fmt::format("{:.1f}", c.delta_bic),
                            c.loso_rms ? fmt::format("{}, {}/{}{}", mv(*c.loso_rms), c.held_out.better, c.held_out.segments, deciding_count(c.held_out))
                                       : std::string("—"),
                            c.plausible ? "yes" : "no: " + c.implausible.front(),
                            fmt::format("{} ({:.2g})", to_string(c.identifiability), c.unique_fraction)});
    }
    doc.add(std::move(candidates));
    add_image(doc, png.candidates, "residual with each candidate effect");
    for (std::size_t k = 0; k < d.candidates.size(); ++k) {
        const auto& c = d.candidates[k];
        if (k >= 3 && c.verdict != Verdict::Supported && c.verdict != Verdict::Partial) break;
        doc.add(Heading{3, fmt::format("{}. `{}`: {}", k + 1, m.spec.with(c.effect).text(), to_string(c.verdict))});
        doc.add(parameter_table(c.fit));
        doc.add(Paragraph{fmt::format("Base parameters against `{}`: Rs {:+.2f} %, Ld {:+.2f} %, Lq {:+.2f} %, psi_f {:+.2f} %.", m.spec.text(),
                                      100 * c.base_shift[0], 100 * c.base_shift[1], 100 * c.base_shift[2], 100 * c.base_shift[3])});
        BulletList implausible;
        for (const auto& why : c.implausible) implausible.items.push_back("implausible: " + why);
        if (!implausible.items.empty()) doc.add(std::move(implausible));
    }
}

// Near ties, what the design cannot identify and what was not tried.
void add_doubts(Document& doc, const Diagnosis& d) {
    const auto& m = d.model;
    doc.add(Heading{2, "How sure"});
    BulletList doubts;
    if (!d.tie.empty()) {
        std::string item = fmt::format("**Near tie** between {}: the evidence cannot order them.", fmt::format("{}", fmt::join(d.tie, ", ")));
        for (const auto& e : d.tie_experiments) item += fmt::format(" Measuring {} ({}) would separate them.", e.name, e.description);
        doubts.items.push_back(item);
    }
    for (const auto& c : d.candidates) {
        if (c.identifiability == Identifiability::Identifiable) continue;
        std::string item = fmt::format("`{}` is {} on this design: {:.2g} of its signature lies outside what `{}` can absorb.", c.effect,
                                       to_string(c.identifiability), c.unique_fraction, m.spec.text());
        for (const auto& e : c.experiments) item += fmt::format(" With {} ({}) it would be {:.2f}.", e.name, e.description, e.unique_after);
        for (const auto& a : c.absorption) {
            item += fmt::format(" At a typical {} = {:.4g}: Rs {:+.1f} %, Ld {:+.1f} %, Lq {:+.1f} %, psi_f {:+.1f} % (residual change {:.2g} noise variances)",
                                a.parameter, a.typical, 100 * a.base_shift[0], 100 * a.base_shift[1], 100 * a.base_shift[2], 100 * a.base_shift[3],
                                a.rss_change);
            for (const auto& [name, value] : a.impossible_from) item += fmt::format("; {} reaches zero at {} = {:.3g}", name, a.parameter, value);
            item += ".";
        }
        doubts.items.push_back(item);
    }
    for (const auto& n : d.not_tried) doubts.items.push_back(fmt::format("`{}` was not tried: the data lack the column `{}`.", n.effect, n.column));
    if (doubts.items.empty()) doc.add(Paragraph{"No near ties, every candidate is identifiable on this design, and every library effect was tried."});
    else doc.add(std::move(doubts));
    doc.add(Paragraph{"How these verdicts are reached: docs/effects.md, \"How diagnose decides\"."});
    if (!d.detection_limits.empty()) {
        doc.add(Heading{3, "Detection limits of this log"});
        doc.add(Paragraph{fmt::format("The smallest size at which each effect that {} leaves out would be found (docs/diagnosis.md, "
                                      "\"Detection limits\", with the rates measured at the limits and at twice them): a smaller one may be "
                                      "present. \"Set by\": the evidence the search asks of an effect, or the voltage it must change "
                                      "(\"relevant size\"), whichever asks more.",
                                      d.recommended.text())});
        Table limits("detection limits", {"parameter", "limit", "unit", "set by", "the effect's default"});
        for (const auto& l : d.detection_limits)
            limits.add_row({l.parameter, std::isfinite(l.limit) ? fmt::format("{:.3g}", l.limit) : std::string("no size shows"), l.unit,
                            l.set_by() ? l.set_by() : "—", fmt::format("{:.3g}", l.typical)});
        doc.add(std::move(limits));
    }
}

}  // namespace

nlohmann::ordered_json operating_points_json(const OperatingPoints& p) {
    nlohmann::ordered_json windows = nlohmann::ordered_json::array();
    for (const auto& w : p.windows) windows.push_back({{"first_row", w.first + 1}, {"rows", w.rows}});
    return {{"found_automatically", true},
            {"method", "moving-sum change-point test on i_d, i_q, omega_e (docs/diagnosis.md)"},
            {"bandwidth_rows", p.bandwidth},
            {"min_rows", p.min_rows},
            {"false_alarm", p.false_alarm},
            {"threshold", p.threshold},
            {"rows", p.rows},
            {"transient_rows", p.transient_rows},
            {"steady_windows", windows}};
}

ReportOutcome write_diagnosis_report(const fs::path& directory, const Measurement& data, const Diagnosis& d, const std::string& data_path,
                                     const std::string& data_options, const FoundOperatingPoints* found) {
    ReportOutcome outcome;
    fs::create_directories(directory);
    const DiagnosisPlots png = draw_diagnosis_plots(directory, data, d, outcome, found);

    Document doc;
    add_summary(doc, d, png, data_path, data_options, found);
    add_fitted_model(doc, d);
    add_where_it_fails(doc, d, data, png);
    add_apparent_parameters(doc, d, png);
    add_candidates(doc, d, png);
    add_doubts(doc, d);
    replace_file(directory / "report.md", markdown(doc));
    outcome.markdown = directory / "report.md";

    // The page and report.md are written from the same document, so the two cannot drift apart.
    HtmlReport page;
    // The diagnosis ran under the --threads cap (a global_control alive while it runs), if any.
    const auto threads = std::min(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
                                  static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
    for (const auto& [label, value] : provenance_lines(current_provenance(static_cast<int>(threads)))) page.add_provenance(label, value);
    page.add_provenance("data", data_path + data_options);
    page.add_provenance("model", d.model.spec.text());
    page.add_document(doc, directory);
    if (outcome.images.empty() && !outcome.notes.empty()) page.add_paragraph("No plots: " + outcome.notes.front() + ".");
    outcome.html = directory / "report.html";
    page.write(outcome.html);
    return outcome;
}

}  // namespace mhb::pmsm

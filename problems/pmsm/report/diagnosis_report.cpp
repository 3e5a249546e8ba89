#include "problems/pmsm/report/diagnosis_report.hpp"

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

namespace mhb::pmsm {
namespace fs = std::filesystem;
namespace {

using json = nlohmann::ordered_json;

json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json rms_json(const AxisRms& r) { return {{"u_d", r.d}, {"u_q", r.q}, {"total", r.total}}; }

json parameters_json(const ModelFit& fit) {
    json p = json::object();
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        json e;
        e["value"] = fit.values[k];
        if (fit.free[j]) {
            e["ci95"] = std::isfinite(fit.lower[k]) ? json::array({fit.lower[k], fit.upper[k]}) : json(nullptr);
            e["standard_error"] = number(fit.standard_error[k]);
        }
        e["unit"] = fit.units[j];
        e["fixed"] = !fit.free[j];
        e["range"] = json::array({fit.range_lower[k], fit.range_upper[k]});
        if (fit.free[j] && j >= 4) e["at_bound"] = fit.at_bound(k);
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

json experiments_json(const std::vector<Experiment>& experiments) {
    json out = json::array();
    for (const auto& e : experiments)
        out.push_back({{"experiment", e.name}, {"operating_point", e.description}, {"unique_fraction_after", e.unique_after}});
    return out;
}

json lack_of_fit_json(const LackOfFit& l) {
    json out{{"significant", l.significant}, {"signature", l.signature}};
    if (l.means_available) out["segment_means"] = {{"statistic", l.statistic}, {"dof", l.dof}, {"p_value", l.p_value}};
    else out["segment_means"] = nullptr;
    json h = json::array();
    for (const auto& x : l.harmonics)
        h.push_back({{"order", x.order}, {"amplitude", {{"u_d", x.amplitude[0]}, {"u_q", x.amplitude[1]}}}, {"standard_error", x.standard_error},
                     {"p_value", x.p_value}});
    out["harmonics"] = h;
    return out;
}

std::string value_text(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : std::string("—"); }

std::string interval_text(const ModelFit& fit, Eigen::Index j) {
    if (!fit.free[static_cast<std::size_t>(j)]) return "fixed";
    if (!std::isfinite(fit.lower[j])) return "not determined by the data";
    return fmt::format("[{:.6g}, {:.6g}]", fit.lower[j], fit.upper[j]);
}

std::string mv(double volts) { return fmt::format("{:.2f}", 1e3 * volts); }

// ---- plots ----

class Plotter {
public:
    Plotter(fs::path directory, ReportOutcome& outcome) : directory_(std::move(directory)), outcome_(outcome) {
        fs::create_directories(directory_ / "plot-data");
    }
    fs::path data(const std::string& name) const { return directory_ / "plot-data" / (name + ".dat"); }
    // Renders and returns the PNG's file name (empty when gnuplot failed; the reason goes to the notes).
    std::string render(const std::string& name, const std::string& body, int width, int height) {
        std::string error;
        if (render_gnuplot(directory_ / name, body, width, height, error)) {
            outcome_.images.push_back(directory_ / (name + ".png"));
            return name + ".png";
        }
        if (std::find(outcome_.notes.begin(), outcome_.notes.end(), error) == outcome_.notes.end()) outcome_.notes.push_back(error);
        return {};
    }

private:
    fs::path directory_;
    ReportOutcome& outcome_;
};

const char* axis_name(int a) { return a == 0 ? "u_d" : "u_q"; }

constexpr const char* model_colour = "#1b6fb5";
constexpr const char* before_colour = "#b0b0b0";

std::string segment_lines(const Diagnosis& d, const Measurement& data) {
    std::string out;
    for (std::size_t s = 1; s < d.segments.size(); ++s) {
        const Eigen::Index k = d.segments[s].first;
        const double x = data.t ? (*data.t)[k] : static_cast<double>(k);
        out += fmt::format("set arrow from {:.9g}, graph 0 to {:.9g}, graph 1 nohead dt 3 lc rgb '#999999'\n", x, x);
    }
    return out;
}

// The model's and the base model's residuals (residual_of), which the two plots below share.
struct PlottedResiduals {
    Eigen::VectorXd model, base;
};

std::string residual_vs_time(Plotter& plot, const Diagnosis& d, const Measurement& data, const PlottedResiduals& residuals) {
    const Eigen::Index n = data.size();
    const bool before = d.build_up.size() > 1;
    const auto& base = d.build_up.front();
    const Eigen::VectorXd& model_residual = residuals.model;
    const Eigen::VectorXd& base_residual = residuals.base;
    const fs::path file = plot.data("residual_time");
    std::ofstream out(file);
    out << "# x r_d r_q before_r_d before_r_q (V)\n";
    for (Eigen::Index k = 0; k < n; ++k)
        out << fmt::format("{:.9g} {:.6g} {:.6g} {:.6g} {:.6g}\n", data.t ? (*data.t)[k] : static_cast<double>(k), model_residual[k],
                           model_residual[n + k], base_residual[k], base_residual[n + k]);
    out.close();
    std::string body = fmt::format("set multiplot layout 2,1 title {} noenhanced\nset grid\nset key top right\n",
                                   gnuplot_quote("Residual (logged minus predicted voltage) through the record; dotted lines: segment changes"));
    body += fmt::format("set xlabel {}\n", gnuplot_quote(data.t ? "t (s)" : "sample"));
    for (int a = 0; a < 2; ++a) {
        body += segment_lines(d, data);
        body += fmt::format("set ylabel {} noenhanced\n", gnuplot_quote(std::string(axis_name(a)) + " residual (V)"));
        std::string plots;
        if (before)
            plots += fmt::format("{} using 1:{} with points pt 7 ps 0.25 lc rgb '{}' title {} noenhanced, ", gnuplot_quote(file.string()), 4 + a,
                                 before_colour, gnuplot_quote(fmt::format("base: {} mV rms", mv(a == 0 ? base.rms.d : base.rms.q))));
        plots += fmt::format("{} using 1:{} with points pt 7 ps 0.25 lc rgb '{}' title {} noenhanced", gnuplot_quote(file.string()), 2 + a,
                             model_colour, gnuplot_quote(fmt::format("{}: {} mV rms", d.model.spec.text(), mv(a == 0 ? d.model.rms.d : d.model.rms.q))));
        body += "plot " + plots + "\nunset arrow\n";
    }
    body += "unset multiplot\n";
    return plot.render("residual_time", body, 1100, 750);
}

std::string residual_vs_angle(Plotter& plot, const Diagnosis& d, const Measurement& data, const PlottedResiduals& residuals) {
    if (!data.theta_e) return {};
    const Eigen::Index n = data.size();
    const bool before = d.build_up.size() > 1;
    const fs::path samples = plot.data("residual_angle"), bins = plot.data("residual_angle_bins");
    std::ofstream out(samples);
    out << "# theta_deg r_d r_q before_r_d before_r_q\n";
    const int count = 72;
    Eigen::ArrayXXd sum = Eigen::ArrayXXd::Zero(count, 4);
    Eigen::ArrayXd hits = Eigen::ArrayXd::Zero(count);
    // Deviations from each segment's mean: the operating points' offsets would otherwise hide what
    // repeats with the angle.
    Eigen::VectorXd model_dev = residuals.model, base_dev = residuals.base;
    for (const auto& s : d.segments)
        for (int a = 0; a < 2; ++a) {
            model_dev.segment(a * n + s.first, s.rows).array() -= s.model.mean[a];
            base_dev.segment(a * n + s.first, s.rows).array() -= s.before.mean[a];
        }
    for (Eigen::Index k = 0; k < n; ++k) {
        const double deg = wrap_angle((*data.theta_e)[k]) * 180.0 / std::numbers::pi;
        const Eigen::Array4d r(model_dev[k], model_dev[n + k], base_dev[k], base_dev[n + k]);
        out << fmt::format("{:.6g} {:.6g} {:.6g} {:.6g} {:.6g}\n", deg, r[0], r[1], r[2], r[3]);
        const int b = std::clamp(static_cast<int>((deg + 180.0) / 360.0 * count), 0, count - 1);
        sum.row(b) += r.transpose();
        hits[b] += 1.0;
    }
    out.close();
    std::ofstream mean(bins);
    mean << "# bin_centre_deg mean_r_d mean_r_q before_mean_r_d before_mean_r_q\n";
    for (int b = 0; b < count; ++b) {
        if (hits[b] == 0) continue;
        mean << fmt::format("{:.6g}", -180.0 + (b + 0.5) * 360.0 / count);
        for (int c = 0; c < 4; ++c) mean << fmt::format(" {:.6g}", sum(b, c) / hits[b]);
        mean << "\n";
    }
    mean.close();
    std::string body = fmt::format("set multiplot layout 2,1 title {} noenhanced\nset grid\nset key top right\nset xrange [-180:180]\nset xtics 60\n",
                                   gnuplot_quote("Residual minus its segment mean against the electrical angle (dots: samples, line: mean in 5-degree bins)"));
    body += "set xlabel 'electrical angle theta_e (degrees)' noenhanced\n";
    for (int a = 0; a < 2; ++a) {
        body += fmt::format("set ylabel {} noenhanced\n", gnuplot_quote(std::string(axis_name(a)) + " residual - segment mean (V)"));
        std::string plots;
        if (before)
            plots += fmt::format("{} using 1:{} with points pt 7 ps 0.2 lc rgb '#dddddd' notitle, {} using 1:{} with lines lw 2 lc rgb '#888888' title 'base' noenhanced, ",
                                 gnuplot_quote(samples.string()), 4 + a, gnuplot_quote(bins.string()), 4 + a);
        plots += fmt::format("{} using 1:{} with points pt 7 ps 0.2 lc rgb '#9ec5e8' notitle, {} using 1:{} with lines lw 2 lc rgb '{}' title {} noenhanced",
                             gnuplot_quote(samples.string()), 2 + a, gnuplot_quote(bins.string()), 2 + a, model_colour,
                             gnuplot_quote(d.model.spec.text()));
        body += "plot " + plots + "\n";
    }
    body += "unset multiplot\n";
    return plot.render("residual_angle", body, 1100, 750);
}

// Segment-mean residuals (with +-2 standard errors of noise) against operating conditions.
fs::path write_segment_means(Plotter& plot, const Diagnosis& d) {
    const fs::path file = plot.data("segment_means");
    std::ofstream out(file);
    out << "# index omega_e i_d i_q |i| temp_winding temp_magnet mean_d se_d mean_q se_q before_d before_q label\n";
    for (std::size_t s = 0; s < d.segments.size(); ++s) {
        const auto& c = d.segments[s];
        out << fmt::format("{} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {}\n", s, c.omega, c.i_d, c.i_q,
                           std::hypot(c.i_d, c.i_q), c.temp_winding.value_or(NAN), c.temp_magnet.value_or(NAN), c.model.mean[0],
                           c.mean_standard_error[0], c.model.mean[1], c.mean_standard_error[1], c.before.mean[0], c.before.mean[1],
                           gnuplot_quote(c.label));
    }
    return file;
}

std::string means_against(Plotter& plot, const Diagnosis& d, const fs::path& file, const std::string& name, const std::string& title,
                          const std::vector<std::pair<int, std::string>>& variables) {
    const bool before = d.build_up.size() > 1;
    // One row per variable, u_d beside u_q: two panels a row stay readable on a laptop's screen, where
    // three side by side (current: i_d, i_q, |i|) would have to shrink to two thirds.
    const auto rows = static_cast<int>(variables.size());
    std::string body = fmt::format("set multiplot layout {},2 title {} noenhanced\nset grid\nset key top left font ',9'\nset offsets graph 0.05, graph 0.05, 0, 0\n",
                                   rows, gnuplot_quote(title));
    for (const auto& [column, label] : variables)
        for (int a = 0; a < 2; ++a) {
            body += fmt::format("set xlabel {} noenhanced\nset ylabel {} noenhanced\n", gnuplot_quote(label),
                                gnuplot_quote(std::string("mean ") + axis_name(a) + " residual (V)"));
            std::string plots = fmt::format("0 with lines lc rgb '#444444' notitle, ");
            if (before)
                plots += fmt::format("{} using {}:{} with points pt 6 ps 1.2 lc rgb '#888888' title 'base' noenhanced, ", gnuplot_quote(file.string()),
                                     column, 12 + a);
            plots += fmt::format("{} using {}:{}:(2*${}) with yerrorbars pt 7 ps 1.0 lc rgb '{}' title {} noenhanced", gnuplot_quote(file.string()),
                                 column, 8 + 2 * a, 9 + 2 * a, model_colour, gnuplot_quote(d.model.spec.text() + " (+-2 SE of noise)"));
            body += "plot " + plots + "\n";
        }
    body += "unset multiplot\n";
    return plot.render(name, body, 1100, 360 * rows + 60);
}

std::string segment_rms_bars(Plotter& plot, const Diagnosis& d) {
    const fs::path file = plot.data("segment_rms");
    std::ofstream out(file);
    out << "# label before_total model_total\n";
    for (const auto& c : d.segments) out << fmt::format("{} {:.6g} {:.6g}\n", gnuplot_data_string(c.label), c.before.rms.total, c.model.rms.total);
    out.close();
    const double floor = std::sqrt((d.noise.sigma.squaredNorm()) / 2.0);
    std::string body = fmt::format("set title {} noenhanced\nset style data histograms\nset style histogram clustered gap 1\n",
                                   gnuplot_quote("Residual rms per segment (u_d and u_q combined); dashed: noise floor"));
    body += "set style fill solid 0.85 border -1\nset boxwidth 0.9\nset grid y\nset ylabel 'rms residual (V)'\nset yrange [0:*]\n";
    body += "set xtics rotate by -35 noenhanced font ',9'\nset key top right\nset bmargin 9\n";
    std::string plots;
    if (d.build_up.size() > 1)
        plots += fmt::format("{} using 2:xtic(1) lc rgb '{}' title 'base', ", gnuplot_quote(file.string()), before_colour);
    plots += fmt::format("{} using 3{} lc rgb '{}' title {} noenhanced, {:.6g} with lines dt 2 lw 2 lc rgb '#c0392b' title {}", gnuplot_quote(file.string()),
                         d.build_up.size() > 1 ? "" : ":xtic(1)", model_colour, gnuplot_quote(d.model.spec.text()), floor,
                         gnuplot_quote(fmt::format("noise floor {} mV", mv(floor))));
    body += "plot " + plots + "\n";
    return plot.render("segment_rms", body, 1100, 600);
}

std::string apparent_plot(Plotter& plot, const Diagnosis& d) {
    const auto count = static_cast<int>(d.apparent_names.size());
    if (count == 0 || d.segments.empty()) return {};
    const fs::path file = plot.data("apparent_parameters");
    std::ofstream out(file);
    out << "# index label then value standard_error per parameter (NaN: not determined by that segment)\n";
    for (std::size_t s = 0; s < d.segments.size(); ++s) {
        out << s << " " << gnuplot_data_string(d.segments[s].label);
        for (const auto& a : d.segments[s].apparent)
            out << (a.determined ? fmt::format(" {:.8g} {:.8g}", a.value, a.standard_error) : std::string(" NaN NaN"));
        out << "\n";
    }
    out.close();
    const int shown = std::min(count, 8);
    const int columns = shown <= 4 ? 2 : 3;
    const int rows = (shown + columns - 1) / columns;
    std::string body = fmt::format("set multiplot layout {},{} title {} noenhanced\nset grid\nset xtics rotate by -35 font ',7' noenhanced\nset offsets 0.5, 0.5, 0, 0\n",
                                   rows, columns,
                                   gnuplot_quote("Each parameter refitted alone per segment (others at the global fit), +-2 SE; line: global fit"));
    for (int p = 0; p < shown; ++p) {
        const auto j = d.model.index_of(d.apparent_names[static_cast<std::size_t>(p)]);
        body += fmt::format("set title {} noenhanced\n", gnuplot_quote(d.apparent_names[static_cast<std::size_t>(p)] + " (" +
                                                                        d.model.units[static_cast<std::size_t>(j)] + ")"));
        body += fmt::format("plot {} using 1:{}:(2*${}):xtic(2) with yerrorbars pt 7 lc rgb '{}' notitle, {:.10g} with lines lc rgb '#c0392b' notitle\n",
                            gnuplot_quote(file.string()), 3 + 2 * p, 4 + 2 * p, model_colour, d.model.values[j]);
    }
    body += "unset multiplot\n";
    return plot.render("apparent_parameters", body, 1100, 330 * rows + 120);
}

// The residual after each step of the search over sets of effects, falling to the noise floor.
std::string path_plot(Plotter& plot, const Diagnosis& d) {
    if (d.path.size() < 2) return {};
    const fs::path file = plot.data("path");
    std::ofstream out(file);
    out << "# step label rms_total rms_u_d rms_u_q plausible\n";
    for (std::size_t k = 0; k < d.path.size(); ++k) {
        const auto& step = d.path[k];
        out << fmt::format("{} {} {:.6g} {:.6g} {:.6g} {}\n", k, gnuplot_data_string(step.change().empty() ? step.fit.spec.text() : step.change()),
                           step.fit.rms.total, step.fit.rms.d, step.fit.rms.q, step.plausible ? 1 : 0);
    }
    out.close();
    const double floor = std::sqrt(d.noise.sigma.squaredNorm() / 2.0);
    // The implausible marker (and its key entry) only when some step has implausible values.
    const bool any_implausible = std::any_of(d.path.begin(), d.path.end(), [](const PathStep& step) { return !step.plausible; });
    std::string body = fmt::format("set title {} noenhanced\nset grid\nset ylabel 'rms residual (V)'\nset logscale y\n",
                                   gnuplot_quote(any_implausible ? "Residual after each step of the search, down to the noise floor (open circles: implausible values)"
                                                                 : "Residual after each step of the search, down to the noise floor"));
    body += fmt::format("set xrange [-0.4:{}]\nset xtics rotate by -25 noenhanced\nset key top right\nset bmargin 6\n", static_cast<double>(d.path.size()) - 0.6);
    const std::string implausible_series =
        any_implausible ? fmt::format("{} using 1:($6 > 0 ? NaN : $3) with points pt 6 ps 2.5 lw 2 lc rgb '#c0392b' title 'implausible values', ",
                                      gnuplot_quote(file.string()))
                        : std::string();
    body += fmt::format("plot {0} using 1:3:xtic(2) with linespoints lw 2 pt 7 ps 1.5 lc rgb '{1}' title 'u_d and u_q combined', "
                        "{4}"
                        "{0} using 1:4 with linespoints dt 3 pt 4 lc rgb '#777777' title 'u_d', "
                        "{0} using 1:5 with linespoints dt 3 pt 8 lc rgb '#aaaaaa' title 'u_q', "
                        "{2:.6g} with lines dt 2 lw 2 lc rgb '#c0392b' title {3}\n",
                        gnuplot_quote(file.string()), model_colour, floor, gnuplot_quote(fmt::format("noise floor {} mV", mv(floor))),
                        implausible_series);
    return plot.render("path", body, 1000, 520);
}

std::string candidate_plot(Plotter& plot, const Diagnosis& d) {
    if (d.candidates.empty()) return {};
    const fs::path file = plot.data("candidates");
    std::ofstream out(file);
    out << "# rank effect rms_after colour verdict\n";
    auto colour = [](Verdict v) {
        switch (v) {
            case Verdict::Supported: return 0x2e8b57;
            case Verdict::Partial: return 0x8fbc5a;
            case Verdict::Weak: return 0xe6a817;
            case Verdict::NotSupported: return 0x9e9e9e;
            case Verdict::Implausible: return 0xc0392b;
            case Verdict::NotIdentifiable: return 0x7d5ba6;
        }
        return 0;
    };
    for (std::size_t k = 0; k < d.candidates.size(); ++k)
        out << fmt::format("{} {} {:.6g} {} {}\n", k, gnuplot_data_string("+" + d.candidates[k].effect), d.candidates[k].fit.rms.total,
                           colour(d.candidates[k].verdict), gnuplot_data_string(to_string(d.candidates[k].verdict)));
    out.close();
    const double floor = std::sqrt((d.noise.sigma.squaredNorm()) / 2.0);
    std::string body = fmt::format("set title {} noenhanced\nset style fill solid 0.85 border -1\nset boxwidth 0.7\nset grid y\n",
                                   gnuplot_quote("Residual rms with each library effect added, best ranked first"));
    body += "set ylabel 'rms residual (V)'\nset yrange [0:*]\nset xtics rotate by -30 noenhanced\nset key outside right top\nset bmargin 6\n";
    body += fmt::format("set xrange [-0.6:{}]\n", static_cast<double>(d.candidates.size()) - 0.4);
    std::string plots = fmt::format("{} using 1:3:4:xtic(2) with boxes lc rgb variable notitle", gnuplot_quote(file.string()));
    for (Verdict v : {Verdict::Supported, Verdict::Partial, Verdict::Weak, Verdict::NotSupported, Verdict::Implausible, Verdict::NotIdentifiable})
        plots += fmt::format(", NaN with boxes lc rgb '#{:06x}' title {}", colour(v), gnuplot_quote(to_string(v)));
    plots += fmt::format(", {:.6g} with lines lw 2 lc rgb '#1b6fb5' title {} noenhanced", d.model.rms.total,
                         gnuplot_quote(d.model.spec.text() + " alone"));
    plots += fmt::format(", {:.6g} with lines dt 2 lw 2 lc rgb '#c0392b' title 'noise floor'", floor);
    body += "plot " + plots + "\n";
    return plot.render("candidates", body, 1100, 560);
}

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

}  // namespace

Measurement read_settled_measurement(const fs::path& path, double settle, const ColumnMap& map) {
    Measurement all = read_measurement(path, map);
    const auto rows = settled_rows(all, settle);
    if (rows.size() < 10)
        throw InputError(path.string(), 0, "settle",
                         fmt::format("dropping {} s after each segment start leaves {} samples; at least 10 are needed", settle, rows.size()));
    return select_rows(std::move(all), rows);
}

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
    out["segments"] = segments_json(fit.segments);
    return out;
}

json diagnosis_json(const Diagnosis& d) {
    json out = fit_json(d.model);
    out["data"] = d.source;
    out["columns"] = d.columns;
    out["missing_effect_found"] = d.missing_effect_found;
    out["winner"] = d.winner ? json(*d.winner) : json(nullptr);
    out["tie"] = d.tie;
    out["tie_experiments"] = experiments_json(d.tie_experiments);
    out["not_in_library"] = d.not_in_library;
    out["recommended_model"] = d.recommended.text();
    json path = json::array();
    for (const auto& step : d.path)
        path.push_back({{"model", step.fit.spec.text()},
                        {"added", step.change().empty() ? json(nullptr) : json(step.change())},
                        {"rms", step.fit.rms.total},
                        {"rms_axes", rms_json(step.fit.rms)},
                        {"dbic", step.delta_bic},
                        {"explained", step.explained},
                        {"plausible", step.plausible},
                        {"implausible", step.implausible},
                        {"at_noise_floor", step.at_noise_floor}});
    out["path"] = path;
    out["pruned"] = d.pruned;
    out["findings"] = d.findings;
    json candidates = json::array();
    for (const auto& c : d.candidates) {
        json e;
        e["effect"] = c.effect;
        e["verdict"] = to_string(c.verdict);
        e["rms_after"] = rms_json(c.fit.rms);
        e["parameters"] = parameters_json(c.fit);
        e["plausible"] = c.plausible;
        e["implausible"] = c.implausible;
        e["added_parameters"] = c.added_parameters;
        e["likelihood_ratio"] = c.likelihood_ratio;
        e["delta_bic"] = c.delta_bic;
        e["explained"] = c.explained;
        e["loso_rms"] = c.loso_rms ? json(*c.loso_rms) : json(nullptr);
        e["loso_better_segments"] = c.loso_segments > 0 ? json::array({c.loso_better, c.loso_segments}) : json(nullptr);
        e["identifiability"] = to_string(c.identifiability);
        e["unique_fraction"] = number(c.unique_fraction);
        e["experiments"] = experiments_json(c.experiments);
        json absorption = json::array();
        for (const auto& a : c.absorption) {
            json shift, zero = json::object();
            for (int j = 0; j < 4; ++j) shift[base_parameter_names[static_cast<std::size_t>(j)]] = a.base_shift[j];
            for (const auto& [name, value] : a.impossible_from) zero[name] = value;
            absorption.push_back({{"parameter", a.parameter}, {"typical", a.typical}, {"base_shift", shift}, {"rss_change", a.rss_change},
                                  {"zero_at", zero}});
        }
        e["absorption"] = absorption;
        json shift;
        for (int j = 0; j < 4; ++j) shift[base_parameter_names[static_cast<std::size_t>(j)]] = c.base_shift[j];
        e["base_shift"] = shift;
        candidates.push_back(e);
    }
    out["candidates"] = candidates;
    json not_tried = json::array();
    for (const auto& n : d.not_tried) not_tried.push_back({{"effect", n.effect}, {"needs", n.column}});
    out["not_tried"] = not_tried;
    out["noise"] = {{"measured_on", d.noise.model},
                    {"sigma", {{"u_d", d.noise.sigma[0]}, {"u_q", d.noise.sigma[1]}}},
                    {"long_run_sigma", {{"u_d", d.noise.long_run[0]}, {"u_q", d.noise.long_run[1]}}},
                    {"effective_samples", d.noise.effective_samples},
                    {"dispersion", d.noise.dispersion}};
    out["lack_of_fit"] = lack_of_fit_json(d.lack_of_fit);
    if (d.after_winner) out["lack_of_fit_after_winner"] = lack_of_fit_json(*d.after_winner);
    out["loso_rms"] = d.model_loso_rms ? json(*d.model_loso_rms) : json(nullptr);
    out["base_plausible"] = d.base_plausible;
    out["base_problems"] = d.base_problems;
    json steps = json::array();
    for (const auto& s : d.build_up) steps.push_back({{"model", s.spec.text()}, {"rms", rms_json(s.rms)}});
    out["steps"] = steps;
    json segments = json::array();
    for (const auto& s : d.segments) {
        json e{{"label", s.label}, {"rows", s.rows}, {"omega_e", s.omega}, {"i_d", s.i_d}, {"i_q", s.i_q}};
        if (s.temp_winding) e["temp_winding"] = *s.temp_winding;
        if (s.temp_magnet) e["temp_magnet"] = *s.temp_magnet;
        e["rms"] = rms_json(s.model.rms);
        e["rms_before"] = rms_json(s.before.rms);
        e["mean_residual"] = {{"u_d", s.model.mean[0]}, {"u_q", s.model.mean[1]}};
        e["mean_standard_error"] = {{"u_d", s.mean_standard_error[0]}, {"u_q", s.mean_standard_error[1]}};
        json apparent;
        for (std::size_t p = 0; p < d.apparent_names.size(); ++p) {
            const auto& a = s.apparent[p];
            apparent[d.apparent_names[p]] = a.determined ? json{{"value", a.value}, {"standard_error", a.standard_error}} : json(nullptr);
        }
        e["apparent"] = apparent;
        segments.push_back(e);
    }
    out["segments"] = segments;
    json drifts = json::array();
    for (const auto& x : d.drifts)
        drifts.push_back({{"parameter", x.parameter}, {"with", x.variable.empty() ? json(nullptr) : json(x.variable)}, {"correlation", x.correlation}, {"slope", x.slope}});
    out["drifts"] = drifts;
    return out;
}

std::string fit_text(const ModelFit& fit, const Measurement& data) {
    std::string t = fmt::format("data: {} ({} samples{})\n", data.source, data.size(),
                                data.has_segments() ? fmt::format(" in {} segments", data.segment_labels.size()) : std::string());
    t += fmt::format("model: {}\nfitted by {}\n\n", fit.spec.text(), fit.method);
    t += fmt::format("{:<28} {:>14} {:>36}  {}\n", "parameter", "value", "95 % interval", "unit");
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        t += fmt::format("{:<28} {:>14} {:>36}  {}{}\n", fit.names[j], value_text(fit.values[k]), interval_text(fit, k), fit.units[j],
                         fit.at_bound(k) ? "  (at a bound of its plausible range)" : "");
    }
    t += fmt::format("\nresidual rms: u_d {:.4g} V, u_q {:.4g} V, combined {:.4g} V\n", fit.rms.d, fit.rms.q, fit.rms.total);
    if (fit.segments.size() > 1) {
        t += fmt::format("\n{:<28} {:>6} {:>11} {:>11} {:>11}\n", "segment", "rows", "u_d (V)", "u_q (V)", "total (V)");
        for (const auto& s : fit.segments)
            t += fmt::format("{:<28} {:>6} {:>11.4g} {:>11.4g} {:>11.4g}\n", s.label, s.rows, s.rms.d, s.rms.q, s.rms.total);
    }
    return t;
}

static std::string path_text(const Diagnosis& d) {
    std::string t = "search over sets of effects:\n";
    t += fmt::format("  {:<52} {:>10} {:>11} {:>10}  {}\n", "model", "rms (V)", "dBIC", "explained", "plausible");
    for (const auto& step : d.path)
        t += fmt::format("  {:<52} {:>10.4g} {:>11} {:>9.0f}%  {}{}\n", (step.change().empty() ? "" : step.change() + " -> ") + step.fit.spec.text(),
                         step.fit.rms.total, step.change().empty() ? std::string("—") : fmt::format("{:.1f}", step.delta_bic), 100.0 * step.explained,
                         step.plausible ? "yes" : "no", step.at_noise_floor ? ", at the noise floor" : "");
    t += fmt::format("recommended model: {}\n", d.recommended.text());
    return t;
}

std::string diagnosis_text(const Diagnosis& d) {
    std::string t = fmt::format("data: {} ({} samples in {} segments)\nmodel: {}: residual rms u_d {:.4g} V, u_q {:.4g} V, combined {:.4g} V\n\n",
                                d.source, d.samples, d.segments.size(), d.model.spec.text(), d.model.rms.d, d.model.rms.q, d.model.rms.total);
    t += fmt::format("{:<4} {:<16} {:<17} {:>12} {:>11} {:>12} {}\n", "rank", "added effect", "verdict", "rms after (V)", "dBIC", "LOSO (V)",
                     "identifiability");
    for (std::size_t k = 0; k < d.candidates.size(); ++k) {
        const auto& c = d.candidates[k];
        t += fmt::format("{:<4} {:<16} {:<17} {:>12.4g} {:>11.1f} {:>12} {}\n", k + 1, c.effect, to_string(c.verdict), c.fit.rms.total, c.delta_bic,
                         c.loso_rms ? fmt::format("{:.4g}", *c.loso_rms) : std::string("—"), to_string(c.identifiability));
    }
    t += "\n" + path_text(d) + "\n";
    for (const auto& f : d.findings) t += "- " + f + "\n";
    return t;
}

ReportOutcome write_diagnosis_report(const fs::path& directory, const Measurement& data, const Diagnosis& d, const std::string& data_path,
                                     const std::string& data_options) {
    ReportOutcome outcome;
    fs::create_directories(directory);
    Plotter plot(directory, outcome);
    PlottedResiduals residuals;
    Eigen::VectorXd storage;
    residuals.model = residual_of(data, d.model, storage);
    residuals.base = residual_of(data, d.build_up.front(), storage);
    const std::string time_png = residual_vs_time(plot, d, data, residuals);
    const std::string angle_png = residual_vs_angle(plot, d, data, residuals);
    const fs::path means = write_segment_means(plot, d);
    const std::string speed_png = means_against(plot, d, means, "residual_speed", "Segment-mean residual against speed", {{2, "omega_e (rad/s)"}});
    const std::string current_png =
        means_against(plot, d, means, "residual_current", "Segment-mean residual against current", {{3, "i_d (A)"}, {4, "i_q (A)"}, {5, "|i| (A)"}});
    std::vector<std::pair<int, std::string>> temperatures;
    if (data.temp_winding) temperatures.emplace_back(6, "winding temperature (degC)");
    if (data.temp_magnet) temperatures.emplace_back(7, "magnet temperature (degC)");
    const std::string temperature_png = temperatures.empty() ? std::string()
                                                             : means_against(plot, d, means, "residual_temperature",
                                                                             "Segment-mean residual against temperature", temperatures);
    const std::string rms_png = segment_rms_bars(plot, d);
    const std::string apparent_png = apparent_plot(plot, d);
    const std::string candidates_png = candidate_plot(plot, d);
    const std::string path_png = path_plot(plot, d);

    const auto& m = d.model;
    Document doc;
    doc.add(Heading{1, fmt::format("Diagnosis of `{}` on `{}`", m.spec.text(), data_path)});
    doc.add(Paragraph{fmt::format("{} samples in {} segments; optional columns: {}.", d.samples, d.segments.size(),
                                  d.columns.empty() ? std::string("none") : fmt::format("{}", fmt::join(d.columns, ", ")))});
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
                                      ? (d.not_in_library ? " (no set of library effects reaches the noise floor with plausible values)" : " (nothing is missing)")
                                      : "")});
    add_image(doc, path_png, "residual after each step of the search");
    if (d.recommended.text() != m.spec.text() || !d.tie.empty()) {
        const std::string next = d.recommended.text() != m.spec.text() ? d.recommended.text() : m.spec.with(d.tie.front()).text();
        doc.add(Paragraph{"Next step:"});
        doc.add(Preformatted{fmt::format("mhbench fit --data {}{} --model {}\nmhbench diagnose --data {}{} --model {} --report <dir>", data_path,
                                         data_options, next, data_path, data_options, next)});
    }

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
    Table segments("residual per segment", std::move(segment_columns));
    for (const auto& s : d.segments) {
        std::vector<Cell> row{s.label, fmt::format("{:.2f}", s.omega), fmt::format("{:.4f}", s.i_d), fmt::format("{:.4f}", s.i_q)};
        if (tw) row.emplace_back(fmt::format("{:.1f}", *s.temp_winding));
        if (tm) row.emplace_back(fmt::format("{:.1f}", *s.temp_magnet));
        if (base_shown) row.emplace_back(mv(s.before.rms.total));
        row.emplace_back(mv(s.model.rms.total));
        row.emplace_back(mv(s.model.mean[0]) + " ± " + mv(s.mean_standard_error[0]));
        row.emplace_back(mv(s.model.mean[1]) + " ± " + mv(s.mean_standard_error[1]));
        segments.add_row(std::move(row));
    }
    doc.add(std::move(segments));
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
    add_image(doc, rms_png, "residual rms per segment");
    add_image(doc, time_png, "residual against time");
    add_image(doc, angle_png, "residual against the electrical angle");
    add_image(doc, speed_png, "segment-mean residual against speed");
    add_image(doc, current_png, "segment-mean residual against current");
    add_image(doc, temperature_png, "segment-mean residual against temperature");

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
    add_image(doc, apparent_png, "parameters refitted per segment");

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
                            c.loso_rms ? fmt::format("{}, {}/{}", mv(*c.loso_rms), c.loso_better, c.loso_segments) : std::string("—"),
                            c.plausible ? "yes" : "no: " + c.implausible.front(),
                            fmt::format("{} ({:.2g})", to_string(c.identifiability), c.unique_fraction)});
    }
    doc.add(std::move(candidates));
    add_image(doc, candidates_png, "residual with each candidate effect");
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
    replace_file(directory / "report.md", markdown(doc));
    outcome.markdown = directory / "report.md";

    // The page and report.md are written from the same document, so the two cannot drift apart.
    HtmlReport page;
    // The diagnosis ran under the --threads cap (a global_control alive while it runs), if any.
    const auto threads = std::min(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism),
                                  static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
    for (const auto& [label, value] : provenance_lines(current_provenance(static_cast<int>(threads)))) page.add_provenance(label, value);
    page.add_provenance("data", data_path + data_options);
    page.add_provenance("model", m.spec.text());
    page.add_document(doc, directory);
    if (outcome.images.empty() && !outcome.notes.empty()) page.add_paragraph("No plots: " + outcome.notes.front() + ".");
    outcome.html = directory / "report.html";
    page.write(outcome.html);
    return outcome;
}

}  // namespace mhb::pmsm

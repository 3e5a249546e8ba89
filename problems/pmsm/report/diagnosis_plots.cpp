#include "problems/pmsm/report/diagnosis_plots.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>

#include <fmt/format.h>

#include "framework/plots.hpp"
#include "problems/pmsm/report/fit_report.hpp"

namespace mhb::pmsm {
namespace fs = std::filesystem;
namespace {

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
constexpr const char* recommended_colour = "#2e8b57";

std::string segment_lines(const Diagnosis& d, const Measurement& data) {
    std::string out;
    for (std::size_t s = 1; s < d.segments.size(); ++s) {
        const Eigen::Index k = d.segments[s].first;
        const double x = data.t ? (*data.t)[k] : static_cast<double>(k);
        out += fmt::format("set arrow from {:.9g}, graph 0 to {:.9g}, graph 1 nohead dt 3 lc rgb '#999999'\n", x, x);
    }
    return out;
}

// The model's and the base model's residuals (residual_of), which the two plots below share, and
// the recommended model's when the search recommends another than these: the same plots then show
// what the recommendation leaves beside what the model diagnosed leaves.
struct PlottedResiduals {
    Eigen::VectorXd model, base, recommended;
};

std::string recommended_title(const ModelFit& fit) { return "recommended " + fit.spec.text(); }

// Writes x(k) and each series' value at row k, a row per line, for the n rows in order; more than
// `most` rows as each of `columns` runs of consecutive rows in two lines: every series' lowest and
// highest value of the run, in the order they occur, at the run's first and last x. A line or a
// band of points through them passes every row's value, so a spike of one row keeps its full height
// where thinning would drop it, and a million-row log's plot stays a few thousand points (an SVG of
// every row of a million would be hundreds of MB). Returns whether it wrote extremes.
template <class X, class Series>
bool write_rows_or_extremes(std::ostream& out, Eigen::Index n, Eigen::Index most, Eigen::Index columns, X x, const std::vector<Series>& series) {
    const bool extremes = n > most;
    if (!extremes) {
        for (Eigen::Index k = 0; k < n; ++k) {
            out << fmt::format("{:.9g}", x(k));
            for (const auto& y : series) out << fmt::format(" {:.6g}", y(k));
            out << "\n";
        }
        return false;
    }
    for (Eigen::Index b = 0; b < columns; ++b) {
        const Eigen::Index first = b * n / columns, end = (b + 1) * n / columns;
        std::string early = fmt::format("{:.9g}", x(first)), late = fmt::format("{:.9g}", x(end - 1));
        for (const auto& y : series) {
            Eigen::Index low = first, high = first;
            for (Eigen::Index k = first + 1; k < end; ++k) {
                if (y(k) < y(low)) low = k;
                if (y(k) > y(high)) high = k;
            }
            early += fmt::format(" {:.6g}", y(std::min(low, high)));
            late += fmt::format(" {:.6g}", y(std::max(low, high)));
        }
        out << early << "\n" << late << "\n";
    }
    return true;
}

// A record's residual plot shows every row up to this many (an SVG of about 10 MB at most); a longer
// one its extremes over this many runs of rows.
constexpr Eigen::Index residual_plot_rows = 20000, residual_plot_columns = 2000;

std::string residual_vs_time(Plotter& plot, const Diagnosis& d, const Measurement& data, const PlottedResiduals& residuals) {
    const Eigen::Index n = data.size();
    const bool before = d.build_up.size() > 1;
    const auto& base = d.build_up.front();
    const Eigen::VectorXd& model_residual = residuals.model;
    const Eigen::VectorXd& base_residual = residuals.base;
    const Eigen::VectorXd& recommended_residual = residuals.recommended;
    const ModelFit* recommended = recommended_to_show(d);
    const fs::path file = plot.data("residual_time");
    std::ofstream out(file);
    const bool extremes = n > residual_plot_rows;
    const std::string columns = std::string("x r_d r_q before_r_d before_r_q") + (recommended ? " recommended_r_d recommended_r_q" : "");
    out << (extremes ? fmt::format("# {} (V): each of {} runs of rows as its lowest and highest values\n", columns, residual_plot_columns)
                     : fmt::format("# {} (V)\n", columns));
    using Row = std::function<double(Eigen::Index)>;
    std::vector<Row> series{[&](Eigen::Index k) { return model_residual[k]; }, [&](Eigen::Index k) { return model_residual[n + k]; },
                            [&](Eigen::Index k) { return base_residual[k]; }, [&](Eigen::Index k) { return base_residual[n + k]; }};
    if (recommended) {
        series.emplace_back([&](Eigen::Index k) { return recommended_residual[k]; });
        series.emplace_back([&](Eigen::Index k) { return recommended_residual[n + k]; });
    }
    write_rows_or_extremes(out, n, residual_plot_rows, residual_plot_columns, [&](Eigen::Index k) { return data.t ? (*data.t)[k] : static_cast<double>(k); },
                           series);
    out.close();
    const std::string title = std::string("Residual (logged minus predicted voltage) through the record; dotted lines: segment changes") +
                              (extremes ? fmt::format("; band: the extremes of each run of about {} of the {} rows",
                                                      (n + residual_plot_columns - 1) / residual_plot_columns, n)
                                        : std::string());
    // Extremes drawn as points would show two bands with nothing between; a line through them,
    // lowest to highest run by run, fills the band the rows span.
    const std::string style = extremes ? "with lines lw 1" : "with points pt 7 ps 0.25";
    std::string body = fmt::format("set multiplot layout 2,1 title {} noenhanced\nset grid\nset key top right\n", gnuplot_quote(title));
    body += fmt::format("set xlabel {}\n", gnuplot_quote(data.t ? "t (s)" : "sample"));
    for (int a = 0; a < 2; ++a) {
        body += segment_lines(d, data);
        body += fmt::format("set ylabel {} noenhanced\n", gnuplot_quote(std::string(axis_name(a)) + " residual (V)"));
        std::string plots;
        if (before)
            plots += fmt::format("{} using 1:{} {} lc rgb '{}' title {} noenhanced, ", gnuplot_quote(file.string()), 4 + a, style,
                                 before_colour, gnuplot_quote(fmt::format("base: {} mV rms", mv(a == 0 ? base.rms.d : base.rms.q))));
        plots += fmt::format("{} using 1:{} {} lc rgb '{}' title {} noenhanced", gnuplot_quote(file.string()), 2 + a, style,
                             model_colour, gnuplot_quote(fmt::format("{}: {} mV rms", d.model.spec.text(), mv(a == 0 ? d.model.rms.d : d.model.rms.q))));
        // Drawn last, over the model diagnosed: what the recommendation leaves lies inside its spread.
        if (recommended)
            plots += fmt::format(", {} using 1:{} {} lc rgb '{}' title {} noenhanced", gnuplot_quote(file.string()), 6 + a, style, recommended_colour,
                                 gnuplot_quote(fmt::format("{}: {} mV rms", recommended_title(*recommended),
                                                           mv(a == 0 ? recommended->rms.d : recommended->rms.q))));
        body += "plot " + plots + "\nunset arrow\n";
    }
    body += "unset multiplot\n";
    return plot.render("residual_time", body, 1100, 750);
}

std::string residual_vs_angle(Plotter& plot, const Diagnosis& d, const Measurement& data, const PlottedResiduals& residuals) {
    if (!data.theta_e) return {};
    const Eigen::Index n = data.size();
    const bool before = d.build_up.size() > 1;
    const ModelFit* recommended = recommended_to_show(d);
    const Eigen::Index width = recommended ? 6 : 4;  // r_d r_q before_r_d before_r_q [recommended_r_d recommended_r_q]
    const fs::path samples = plot.data("residual_angle"), bins = plot.data("residual_angle_bins");
    std::ofstream out(samples);
    out << (recommended ? "# theta_deg r_d r_q before_r_d before_r_q recommended_r_d recommended_r_q\n" : "# theta_deg r_d r_q before_r_d before_r_q\n");
    const int count = 72;
    Eigen::ArrayXXd sum = Eigen::ArrayXXd::Zero(count, width);
    Eigen::ArrayXd hits = Eigen::ArrayXd::Zero(count);
    // Deviations from each segment's mean: the operating points' offsets would otherwise hide what
    // repeats with the angle.
    Eigen::VectorXd model_dev = residuals.model, base_dev = residuals.base, recommended_dev = residuals.recommended;
    for (std::size_t k = 0; k < d.segments.size(); ++k) {
        const auto& s = d.segments[k];
        for (int a = 0; a < 2; ++a) {
            model_dev.segment(a * n + s.first, s.rows).array() -= s.model.mean[a];
            base_dev.segment(a * n + s.first, s.rows).array() -= s.before.mean[a];
            if (recommended) recommended_dev.segment(a * n + s.first, s.rows).array() -= recommended->segments[k].mean[a];
        }
    }
    // A longer record: each of residual_plot_columns columns of angle as its lowest and highest
    // value of each series, at the column's centre (the bins' means below stay the mean of all rows).
    const bool extremes = n > residual_plot_rows;
    const Eigen::Index angle_columns = residual_plot_columns;
    Eigen::ArrayXXd lowest, highest;
    if (extremes) {
        lowest = Eigen::ArrayXXd::Constant(angle_columns, width, std::numeric_limits<double>::infinity());
        highest = Eigen::ArrayXXd::Constant(angle_columns, width, -std::numeric_limits<double>::infinity());
    }
    auto write_line = [&](double x, const auto& values) {
        out << fmt::format("{:.6g}", x);
        for (Eigen::Index c = 0; c < width; ++c) out << fmt::format(" {:.6g}", values(c));
        out << "\n";
    };
    Eigen::ArrayXd r(width);
    for (Eigen::Index k = 0; k < n; ++k) {
        const double deg = wrap_angle((*data.theta_e)[k]) * 180.0 / std::numbers::pi;
        r.head(4) << model_dev[k], model_dev[n + k], base_dev[k], base_dev[n + k];
        if (recommended) r.tail(2) << recommended_dev[k], recommended_dev[n + k];
        if (extremes) {
            const Eigen::Index c = std::clamp(static_cast<Eigen::Index>((deg + 180.0) / 360.0 * static_cast<double>(angle_columns)), Eigen::Index{0},
                                              angle_columns - 1);
            lowest.row(c) = lowest.row(c).min(r.transpose());
            highest.row(c) = highest.row(c).max(r.transpose());
        } else {
            write_line(deg, r);
        }
        const int b = std::clamp(static_cast<int>((deg + 180.0) / 360.0 * count), 0, count - 1);
        sum.row(b) += r.transpose();
        hits[b] += 1.0;
    }
    for (Eigen::Index c = 0; extremes && c < angle_columns; ++c) {
        if (!std::isfinite(lowest(c, 0))) continue;
        const double centre = -180.0 + (static_cast<double>(c) + 0.5) * 360.0 / static_cast<double>(angle_columns);
        write_line(centre, lowest.row(c));
        write_line(centre, highest.row(c));
    }
    out.close();
    std::ofstream mean(bins);
    mean << (recommended ? "# bin_centre_deg mean_r_d mean_r_q before_mean_r_d before_mean_r_q recommended_mean_r_d recommended_mean_r_q\n"
                         : "# bin_centre_deg mean_r_d mean_r_q before_mean_r_d before_mean_r_q\n");
    for (int b = 0; b < count; ++b) {
        // A blank line where no sample fell: gnuplot breaks the line there instead of drawing one
        // across angles the log never reached.
        if (hits[b] == 0) {
            if (b > 0 && hits[b - 1] > 0) mean << "\n";
            continue;
        }
        mean << fmt::format("{:.6g}", -180.0 + (b + 0.5) * 360.0 / count);
        for (Eigen::Index c = 0; c < width; ++c) mean << fmt::format(" {:.6g}", sum(b, c) / hits[b]);
        mean << "\n";
    }
    mean.close();
    std::string body = fmt::format("set multiplot layout 2,1 title {} noenhanced\nset grid\nset key top right\nset xrange [-180:180]\nset xtics 60\n",
                                   gnuplot_quote(extremes ? fmt::format("Residual minus its segment mean against the electrical angle (band: the extremes "
                                                                        "of the {} rows in each of {} columns of angle; line: mean in 5-degree bins)",
                                                                        n, angle_columns)
                                                          : std::string("Residual minus its segment mean against the electrical angle (dots: samples, line: "
                                                                        "mean in 5-degree bins)")));
    const std::string style = extremes ? "with lines lw 1" : "with points pt 7 ps 0.2";
    body += "set xlabel 'electrical angle theta_e (degrees)' noenhanced\n";
    for (int a = 0; a < 2; ++a) {
        body += fmt::format("set ylabel {} noenhanced\n", gnuplot_quote(std::string(axis_name(a)) + " residual - segment mean (V)"));
        std::string plots;
        if (before)
            plots += fmt::format("{} using 1:{} {} lc rgb '#dddddd' notitle, {} using 1:{} with lines lw 2 lc rgb '#888888' title 'base' noenhanced, ",
                                 gnuplot_quote(samples.string()), 4 + a, style, gnuplot_quote(bins.string()), 4 + a);
        plots += fmt::format("{} using 1:{} {} lc rgb '#9ec5e8' notitle, {} using 1:{} with lines lw 2 lc rgb '{}' title {} noenhanced",
                             gnuplot_quote(samples.string()), 2 + a, style, gnuplot_quote(bins.string()), 2 + a, model_colour,
                             gnuplot_quote(d.model.spec.text()));
        // Only the recommendation's bin means: its samples would cover the model's, whose pattern
        // against the angle is what this plot is for.
        if (recommended)
            plots += fmt::format(", {} using 1:{} with lines lw 2 lc rgb '{}' title {} noenhanced", gnuplot_quote(bins.string()), 6 + a, recommended_colour,
                                 gnuplot_quote(recommended_title(*recommended)));
        body += "plot " + plots + "\n";
    }
    body += "unset multiplot\n";
    return plot.render("residual_angle", body, 1100, 750);
}

// Segment-mean residuals (with +-2 standard errors of noise) against operating conditions.
fs::path write_segment_means(Plotter& plot, const Diagnosis& d) {
    const fs::path file = plot.data("segment_means");
    std::ofstream out(file);
    const ModelFit* recommended = recommended_to_show(d);
    out << "# index omega_e i_d i_q |i| temp_winding temp_magnet mean_d se_d mean_q se_q before_d before_q recommended_d recommended_q label "
           "(recommended: NaN when the model diagnosed is the one recommended)\n";
    for (std::size_t s = 0; s < d.segments.size(); ++s) {
        const auto& c = d.segments[s];
        const Eigen::Vector2d after = recommended ? recommended->segments[s].mean : Eigen::Vector2d::Constant(NAN);
        out << fmt::format("{} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {:.6g} {}\n", s, c.omega, c.i_d,
                           c.i_q, std::hypot(c.i_d, c.i_q), c.temp_winding.value_or(NAN), c.temp_magnet.value_or(NAN), c.model.mean[0],
                           c.mean_standard_error[0], c.model.mean[1], c.mean_standard_error[1], c.before.mean[0], c.before.mean[1], after[0], after[1],
                           gnuplot_quote(c.label));
    }
    return file;
}

std::string means_against(Plotter& plot, const Diagnosis& d, const fs::path& file, const std::string& name, const std::string& title,
                          const std::vector<std::pair<int, std::string>>& variables) {
    const bool before = d.build_up.size() > 1;
    const ModelFit* recommended = recommended_to_show(d);
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
            if (recommended)
                plots += fmt::format(", {} using {}:{} with points pt 9 ps 1.3 lc rgb '{}' title {} noenhanced", gnuplot_quote(file.string()), column,
                                     14 + a, recommended_colour, gnuplot_quote(recommended_title(*recommended)));
            body += "plot " + plots + "\n";
        }
    body += "unset multiplot\n";
    return plot.render(name, body, 1100, 360 * rows + 60);
}

std::string segment_rms_bars(Plotter& plot, const Diagnosis& d) {
    const ModelFit* recommended = recommended_to_show(d);
    const fs::path file = plot.data("segment_rms");
    std::ofstream out(file);
    out << (recommended ? "# label before_total model_total recommended_total\n" : "# label before_total model_total\n");
    for (std::size_t s = 0; s < d.segments.size(); ++s) {
        const auto& c = d.segments[s];
        out << fmt::format("{} {:.6g} {:.6g}", gnuplot_data_string(c.label), c.before.rms.total, c.model.rms.total);
        if (recommended) out << fmt::format(" {:.6g}", recommended->segments[s].rms.total);
        out << "\n";
    }
    out.close();
    const double floor = std::sqrt((d.noise.sigma.squaredNorm()) / 2.0);
    std::string body = fmt::format("set title {} noenhanced\nset style data histograms\nset style histogram clustered gap 1\n",
                                   gnuplot_quote("Residual rms per segment (u_d and u_q combined); dashed: noise floor"));
    body += "set style fill solid 0.85 border -1\nset boxwidth 0.9\nset grid y\nset ylabel 'rms residual (V)'\nset yrange [0:*]\n";
    body += "set xtics rotate by -35 noenhanced font ',9'\nset key top right\nset bmargin 9\n";
    // Each bar series: its column and how it is drawn; the first carries the segments' labels.
    std::vector<std::pair<int, std::string>> bars;
    if (d.build_up.size() > 1) bars.emplace_back(2, fmt::format("lc rgb '{}' title 'base'", before_colour));
    bars.emplace_back(3, fmt::format("lc rgb '{}' title {} noenhanced", model_colour, gnuplot_quote(d.model.spec.text())));
    if (recommended) bars.emplace_back(4, fmt::format("lc rgb '{}' title {} noenhanced", recommended_colour, gnuplot_quote(recommended_title(*recommended))));
    std::string plots;
    for (std::size_t k = 0; k < bars.size(); ++k)
        plots += fmt::format("{} using {}{} {}, ", gnuplot_quote(file.string()), bars[k].first, k == 0 ? ":xtic(1)" : "", bars[k].second);
    plots += fmt::format("{:.6g} with lines dt 2 lw 2 lc rgb '#c0392b' title {}", floor, gnuplot_quote(fmt::format("noise floor {} mV", mv(floor))));
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

// Pixel columns of the raw log's plot: a longer log is drawn as each column's extremes.
constexpr Eigen::Index log_plot_columns = 1000;

// The raw log's i_d, i_q, omega_e, u_d and u_q against time (row, counted from 1, without a time
// column), with the steady windows found in it shaded and labelled and the rows dropped as transient
// left white over a red band. A log of more than two rows per pixel column is written as each column's lowest and
// highest value of every channel, in the order they occur: the line through them passes every row's
// value, so a spike of a single row keeps its full height where thinning would drop it.
std::string operating_points_plot(Plotter& plot, const FoundOperatingPoints& found) {
    const Measurement& log = found.log;
    const OperatingPoints& points = found.points;
    const Eigen::Index n = log.size();
    if (n == 0) return {};
    auto x = [&](Eigen::Index k) { return log.t ? (*log.t)[k] : static_cast<double>(k + 1); };
    const std::vector<const Eigen::VectorXd*> channels{&log.i_d, &log.i_q, &log.omega_e, &log.u_d, &log.u_q};
    const fs::path file = plot.data("operating_points_log");
    std::ofstream out(file);
    const bool decimated = n > 2 * log_plot_columns;
    out << (decimated ? fmt::format("# x i_d i_q omega_e u_d u_q: each of {} columns of rows as two lines, its lowest and highest value of each "
                                    "channel in the order they occur (at its first and last row's x)\n",
                                    log_plot_columns)
                      : std::string("# x i_d i_q omega_e u_d u_q: every row\n"));
    std::vector<std::function<double(Eigen::Index)>> series;
    for (const auto* c : channels) series.emplace_back([c](Eigen::Index k) { return (*c)[k]; });
    write_rows_or_extremes(out, n, 2 * log_plot_columns, log_plot_columns, x, series);
    out.close();
    const fs::path windows = plot.data("operating_points_windows");
    std::ofstream listed(windows);
    listed << "# label first_row rows x_first x_last (rows counted from 1, as in the JSON's operating_points)\n";
    for (std::size_t w = 0; w < points.windows.size(); ++w) {
        const auto& window = points.windows[w];
        listed << fmt::format("{} {} {} {:.9g} {:.9g}\n", gnuplot_data_string(fmt::format("steady{}", w + 1)), window.first + 1, window.rows,
                              x(window.first), x(window.first + window.rows - 1));
    }
    listed.close();

    // A transient of a thousand rows in a log of a million is about a pixel column, and a false split
    // of a window no wider: drawn to scale, neither would show (the step through a transient is
    // drawn over it). So a transient is white at least four columns wide over the windows' shading,
    // with a red band along the foot of each panel, and a window narrower than three columns is a
    // dark green mark, two columns wide, in that band.
    const double span = x(n - 1) - x(0), column = span / static_cast<double>(log_plot_columns);
    const std::size_t count = points.windows.size();
    std::vector<double> from(count), to(count);
    for (std::size_t w = 0; w < count; ++w) {
        from[w] = x(points.windows[w].first);
        to[w] = x(points.windows[w].first + points.windows[w].rows - 1);
    }
    auto rectangle = [](double left, double right, double top, const char* colour) {
        return fmt::format("set object rect from {:.9g}, graph 0 to {:.9g}, graph {} fc rgb '{}' fs solid 1.0 noborder behind\n", left, right, top,
                           colour);
    };
    auto at_least = [&](double left, double right, double columns) {
        const double middle = (left + right) / 2.0, half = std::max(right - left, columns * column) / 2.0;
        return std::pair{middle - half, middle + half};
    };
    // gnuplot paints the rectangle defined last on top.
    std::string shading, narrow;
    for (std::size_t w = 0; w < count; ++w) {
        const auto [left, right] = at_least(from[w], to[w], 1.0);
        shading += rectangle(left, right, 1.0, "#cfe8cf");
        if (to[w] - from[w] < 3.0 * column) {
            const auto [mark_left, mark_right] = at_least(from[w], to[w], 2.0);
            narrow += rectangle(mark_left, mark_right, 0.06, "#2e7d32");
        }
    }
    // Each stretch of transient rows, from the row after a window (or the log's first) to the row
    // before the next window (or the log's last).
    Eigen::Index next = 0;
    for (std::size_t w = 0; w <= count; ++w) {
        const Eigen::Index end = w < count ? points.windows[w].first : n;
        if (end > next) {
            const auto [left, right] = at_least(x(next), x(end - 1), 4.0);
            shading += rectangle(left, right, 1.0, "#ffffff") + rectangle(left, right, 0.06, "#d62728");
        }
        if (w < count) next = points.windows[w].first + points.windows[w].rows;
    }
    shading += narrow;
    // Labels stand upright above the top panel, each at its window's middle unless that would write
    // it over the one before: then just after that one, with a line down to its window.
    const double plot_left = 0.08, plot_right = 0.98, width = 1100.0, label_height = 12.0;
    const double pixels_per_x = (plot_right - plot_left) * width / span;
    // More labels than fit across the panel: every k-th, so that none runs off the page.
    const auto every = static_cast<std::size_t>(std::ceil(static_cast<double>(count) * label_height / ((plot_right - plot_left) * width * 0.9)));
    std::string labels;
    double previous = -INFINITY;
    for (std::size_t w = 0; w < count; ++w) {
        if (w % every != 0) continue;
        const double middle = (from[w] + to[w]) / 2.0, at = std::max(middle, previous + label_height / pixels_per_x);
        previous = at;
        labels += fmt::format("set label {} 'steady{}' at {:.9g}, graph 1.07 left rotate by 90 offset 0.35, 0 font ',8' front\n", w + 1, w + 1, at);
        labels += fmt::format("set arrow {} from {:.9g}, graph 1.0 to {:.9g}, graph 1.06 nohead lw 1 lc rgb '#555555' front\n", w + 1, middle, at);
    }
    const std::vector<std::string> names{"i_d (A)", "i_q (A)", "omega_e (rad/s)", "u_d (V)", "u_q (V)"};
    const int panels = static_cast<int>(names.size());
    const std::string title = fmt::format("The log as read: shaded green, the {} steady windows found; white, the {} of {} rows dropped as transient",
                                          count, points.transient_rows, points.rows);
    std::string body = fmt::format("set multiplot layout {},1 title {} noenhanced margins {}, {}, 0.06, 0.86 spacing 0, 0.012\n", panels,
                                   gnuplot_quote(title), plot_left, plot_right);
    body += fmt::format("set grid\nset xrange [{:.9g}:{:.9g}]\nset ytics font ',9'\nset format x ''\n", x(0), x(n - 1));
    const std::string scale = fmt::format("red band: transient (at least 4 pixel columns wide), dark green: a window narrower than 3 columns{}",
                                          decimated ? fmt::format("; about {} rows per column, each drawn from its lowest to its highest value",
                                                                  (n + log_plot_columns - 1) / log_plot_columns)
                                                    : std::string());
    body += fmt::format("set label 1000000 {} at screen 0.5, screen 0.95 center font ',9' noenhanced\n", gnuplot_quote(scale));
    body += shading;
    for (int p = 0; p < panels; ++p) {
        if (p == 0) body += labels;
        if (p == panels - 1) body += fmt::format("set format x '%g'\nset xlabel {}\n", gnuplot_quote(log.t ? "t (s)" : "row"));
        body += fmt::format("set ylabel {} noenhanced\n", gnuplot_quote(names[static_cast<std::size_t>(p)]));
        body += fmt::format("plot {} using 1:{} with lines lw 1 lc rgb '{}' notitle\n", gnuplot_quote(file.string()), 2 + p, model_colour);
        if (p == 0) body += "unset label\nunset arrow\n";
    }
    body += "unset multiplot\n";
    return plot.render("operating_points", body, 1100, 1000);
}

}  // namespace

const ModelFit* recommended_to_show(const Diagnosis& d) {
    const std::string text = d.recommended.text();
    if (text.empty() || text == d.model.spec.text() || (d.build_up.size() > 1 && text == d.build_up.front().spec.text())) return nullptr;
    const ModelFit& fit = d.recommended_fit();
    if (fit.spec.text() != text || fit.segments.size() != d.segments.size()) return nullptr;
    return &fit;
}

DiagnosisPlots draw_diagnosis_plots(const fs::path& directory, const Measurement& data, const Diagnosis& d, ReportOutcome& outcome,
                                    const FoundOperatingPoints* found) {
    DiagnosisPlots out;
    Plotter plot(directory, outcome);
    if (found) out.operating_points = operating_points_plot(plot, *found);
    PlottedResiduals residuals;
    Eigen::VectorXd storage;
    residuals.model = residual_of(data, d.model, storage);
    residuals.base = residual_of(data, d.build_up.front(), storage);
    if (const ModelFit* recommended = recommended_to_show(d)) residuals.recommended = residual_of(data, *recommended, storage);
    out.time = residual_vs_time(plot, d, data, residuals);
    out.angle = residual_vs_angle(plot, d, data, residuals);
    const fs::path means = write_segment_means(plot, d);
    out.speed = means_against(plot, d, means, "residual_speed", "Segment-mean residual against speed", {{2, "omega_e (rad/s)"}});
    out.current = means_against(plot, d, means, "residual_current", "Segment-mean residual against current", {{3, "i_d (A)"}, {4, "i_q (A)"}, {5, "|i| (A)"}});
    std::vector<std::pair<int, std::string>> temperatures;
    if (data.temp_winding) temperatures.emplace_back(6, "winding temperature (degC)");
    if (data.temp_magnet) temperatures.emplace_back(7, "magnet temperature (degC)");
    out.temperature = temperatures.empty() ? std::string()
                                             : means_against(plot, d, means, "residual_temperature",
                                                             "Segment-mean residual against temperature", temperatures);
    out.rms = segment_rms_bars(plot, d);
    out.apparent = apparent_plot(plot, d);
    out.candidates = candidate_plot(plot, d);
    out.path = path_plot(plot, d);
    return out;
}

}  // namespace mhb::pmsm

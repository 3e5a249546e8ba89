#include "problems/pmsm/data/operating_points.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "framework/input_error.hpp"

namespace mhb::pmsm {
namespace {

// A row further than this many of its window's own standard deviations from the window's level
// ends the window. Four keeps a steady row in with probability 1 - 6e-5 per channel, so a window
// is seldom cut short by its own noise, while a step of a few standard deviations still stops it.
constexpr double row_tolerance = 4.0;

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

// 1.4826 median |x - median|: the standard deviation of normal data, unmoved by a minority of outliers.
double robust_sd(const Eigen::Ref<const Eigen::VectorXd>& x) {
    std::vector<double> v(x.data(), x.data() + x.size());
    const double centre = median(v);
    for (auto& e : v) e = std::abs(e - centre);
    return 1.4826 * median(std::move(v));
}

// The long-run standard deviation of a channel at the test's own scale: the means of consecutive
// blocks of G rows differ by sqrt(2 / G) of it where the level holds. Their absolute differences'
// lower quartile gives it unmoved by the blocks that straddle a change, as long as three in four
// blocks are steady (a median would need one in two: a raw log can be mostly settling). It takes in
// the serial correlation (a logging filter, a control loop) and any ripple slower than the blocks,
// which the test must not call changes.
double long_run_scale(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Index g) {
    const Eigen::Index blocks = x.size() / g;
    std::vector<double> differences;
    for (Eigen::Index b = 0; b + 1 < blocks; ++b)
        differences.push_back(std::abs(x.segment((b + 1) * g, g).mean() - x.segment(b * g, g).mean()));
    double quartile = 0.0;
    if (!differences.empty()) {
        const auto q = differences.begin() + static_cast<std::ptrdiff_t>(differences.size() / 4);
        std::nth_element(differences.begin(), q, differences.end());
        quartile = *q;
    }
    // |N(0, s)| has its lower quartile at 0.3186 s (the normal quantile at 5/8).
    const double scale = std::sqrt(static_cast<double>(g) / 2.0) * quartile / 0.31864;
    // A channel without noise (a simulated speed with no sensor noise) still has rounding: a
    // relative floor keeps the test from reading rounding as changes.
    const double floor = 1e-9 * std::max(x.cwiseAbs().maxCoeff(), 1e-300);
    return std::max(scale, floor);
}

// Eichinger and Kirch (Bernoulli 24, 2018, Theorem 2.1): under no change the maximum over the log
// of the standardised moving sum, scaled, tends to a Gumbel law, P(a max T - b <= x) -> exp(-2 e^-x),
// with a = sqrt(2 log(n/G)), b = 2 log(n/G) + log log(n/G) / 2 + log(3/2) - log(pi) / 2.
double moving_sum_threshold(Eigen::Index n, Eigen::Index g, double alpha) {
    const double ratio = std::max(static_cast<double>(n) / static_cast<double>(g), 4.0);
    const double l = std::log(ratio);
    const double a = std::sqrt(2.0 * l);
    const double b = 2.0 * l + 0.5 * std::log(l) + std::log(1.5) - 0.5 * std::log(std::numbers::pi);
    const double c = -std::log(-0.5 * std::log1p(-alpha));
    return (b + c) / a;
}

struct Region {
    Eigen::Index first_flag, last_flag, peak;  // flagged positions k (change between rows k and k + 1)
};

}  // namespace

OperatingPoints find_steady_windows(const Eigen::MatrixXd& x, const OperatingPointOptions& options) {
    return find_steady_windows(x, x, options);
}

OperatingPoints find_steady_windows(const Eigen::MatrixXd& x, const Eigen::MatrixXd& held, const OperatingPointOptions& options) {
    const Eigen::Index n = x.rows(), channels = x.cols(), g = options.bandwidth;
    if (held.rows() != n) throw std::invalid_argument("the channels tested and held must have the same rows");
    if (g < 2) throw std::invalid_argument("the bandwidth of the operating-point test must be at least 2 rows");
    if (!(options.false_alarm > 0.0 && options.false_alarm < 1.0))
        throw std::invalid_argument("the false-alarm probability of the operating-point test must lie in (0, 1)");
    OperatingPoints out;
    out.rows = n;
    out.bandwidth = g;
    out.min_rows = options.min_rows > 0 ? options.min_rows : 3 * g;
    out.false_alarm = options.false_alarm;
    // Each channel at its own level: a Bonferroni share of the false-alarm probability.
    out.threshold = moving_sum_threshold(n, g, options.false_alarm / static_cast<double>(std::max<Eigen::Index>(channels, 1)));

    std::vector<Region> regions;
    std::vector<double> coarse_scale;
    const double coarse_threshold = moving_sum_threshold(n, 4 * g, options.false_alarm / static_cast<double>(std::max<Eigen::Index>(channels, 1)));
    for (Eigen::Index c = 0; c < channels; ++c) coarse_scale.push_back(n >= 8 * g ? long_run_scale(x.col(c), 4 * g) : 0.0);
    if (n >= 2 * g + 1 && channels > 0) {
        Eigen::VectorXd statistic = Eigen::VectorXd::Zero(n);
        for (Eigen::Index c = 0; c < channels; ++c) {
            const double s = long_run_scale(x.col(c), g);
            out.scale.push_back(s);
            Eigen::VectorXd prefix(n + 1);
            prefix[0] = 0.0;
            for (Eigen::Index r = 0; r < n; ++r) prefix[r + 1] = prefix[r] + x(r, c);
            const double norm = s * std::sqrt(2.0 / static_cast<double>(g)) * static_cast<double>(g);
            for (Eigen::Index k = g - 1; k + g < n; ++k) {
                const double left = prefix[k + 1] - prefix[k + 1 - g], right = prefix[k + 1 + g] - prefix[k + 1];
                statistic[k] = std::max(statistic[k], std::abs(right - left) / norm);
            }
        }
        for (Eigen::Index k = 0; k < n; ++k) {
            if (statistic[k] < out.threshold) continue;
            if (!regions.empty() && regions.back().last_flag + 1 == k) {
                regions.back().last_flag = k;
                if (statistic[k] > statistic[regions.back().peak]) regions.back().peak = k;
            } else {
                regions.push_back({k, k, k});
            }
        }
    }

    // Between regions, the rows no flagged comparison reaches: [last_flag + G + 1, next first_flag - G].
    // Each is then widened row by row towards the neighbouring changes' peaks while its rows stay
    // at its level, since a large step is flagged up to G rows before and after it. The level is the
    // window's median, not the mean of its edge rows: an edge can still hold the end of a settling.
    auto level_holds = [&](Eigen::Index row, const Eigen::VectorXd& level, const Eigen::VectorXd& spread) {
        for (Eigen::Index c = 0; c < held.cols(); ++c)
            if (std::abs(held(row, c) - level[c]) > row_tolerance * spread[c]) return false;
        return true;
    };
    for (std::size_t r = 0; r <= regions.size(); ++r) {
        const Eigen::Index lower_bound = r == 0 ? 0 : regions[r - 1].peak + 1;
        const Eigen::Index upper_bound = r == regions.size() ? n - 1 : regions[r].peak;
        Eigen::Index first = r == 0 ? 0 : regions[r - 1].last_flag + g + 1;
        Eigen::Index last = r == regions.size() ? n - 1 : regions[r].first_flag - g;
        if (last - first + 1 < 2) continue;
        Eigen::VectorXd spread(held.cols()), level(held.cols());
        for (Eigen::Index c = 0; c < held.cols(); ++c) {
            const auto column = held.col(c).segment(first, last - first + 1);
            spread[c] = std::max(robust_sd(column), 1e-12 * std::abs(held(first, c)));
            level[c] = median(std::vector<double>(column.data(), column.data() + column.size()));
        }
        // One row off its level is taken for noise (a window of a hundred rows has a few 4-sd
        // excursions in one of three channels now and then); two in a row end the window.
        const auto holds = [&](Eigen::Index row, Eigen::Index next, Eigen::Index bound, bool upward) {
            if (level_holds(row, level, spread)) return true;
            return (upward ? next <= bound : next >= bound) && level_holds(next, level, spread);
        };
        while (first > lower_bound && holds(first - 1, first - 2, lower_bound, false)) --first;
        while (last < upper_bound && holds(last + 1, last + 2, upper_bound, true)) ++last;
        // A settling slower than the test's windows (a speed loop's last overshoot) moves the means
        // of two adjacent windows of G rows too little to be seen, but not the head of the window
        // against its tail: while the first H = 4 G rows differ from the last H by the threshold
        // at that scale, the window's start moves on by G rows.
        const Eigen::Index h = 4 * g;
        while (last - first + 1 >= 3 * h) {
            bool differs = false;
            for (Eigen::Index c = 0; c < channels && !differs; ++c) {
                const double head = x.col(c).segment(first, h).mean(), tail = x.col(c).segment(last - h + 1, h).mean();
                differs = std::abs(head - tail) > coarse_threshold * coarse_scale[static_cast<std::size_t>(c)] *
                                                       std::sqrt(2.0 / static_cast<double>(h));
            }
            if (!differs) break;
            first += g;
        }
        if (last - first + 1 >= out.min_rows) out.windows.push_back({first, last - first + 1});
    }
    Eigen::Index steady = 0;
    for (const auto& w : out.windows) steady += w.rows;
    out.transient_rows = n - steady;
    return out;
}

OperatingPoints find_operating_points(const Measurement& m, const OperatingPointOptions& options) {
    Eigen::MatrixXd tested(m.size(), 3), held(m.size(), 5);
    tested.col(0) = m.i_d;
    tested.col(1) = m.i_q;
    tested.col(2) = m.omega_e;
    held.leftCols(3) = tested;
    // The voltages are held too, but not tested: a drive logs its new voltage reference in the
    // very sample its reference changes, a sample before the currents answer; and the slow
    // harmonics a dead time leaves in them are no change of operating point.
    held.col(3) = m.u_d;
    held.col(4) = m.u_q;
    auto points = find_steady_windows(tested, held, options);
    points.channels = {"i_d", "i_q", "omega_e"};
    return points;
}

Measurement select_operating_points(Measurement&& m, const OperatingPoints& points) {
    if (points.windows.empty())
        throw InputError(m.source, 0, "segment",
                         fmt::format("the log has no segment column and no steady window of at least {} rows was found in its "
                                     "{} rows (i_d, i_q and omega_e change throughout); give a segment column",
                                     points.min_rows, m.size()));
    std::vector<Eigen::Index> rows;
    std::vector<int> labels;
    for (std::size_t w = 0; w < points.windows.size(); ++w)
        for (Eigen::Index k = 0; k < points.windows[w].rows; ++k) {
            rows.push_back(points.windows[w].first + k);
            labels.push_back(static_cast<int>(w));
        }
    Measurement steady = select_rows(std::move(m), rows);
    steady.segment_labels.clear();
    for (std::size_t w = 0; w < points.windows.size(); ++w) steady.segment_labels.push_back(fmt::format("steady{}", w + 1));
    steady.segment = Eigen::Map<const Eigen::VectorXi>(labels.data(), static_cast<Eigen::Index>(labels.size()));
    return steady;
}

std::optional<OperatingPoints> segment_at_operating_points(Measurement& m, const OperatingPointOptions& options) {
    if (m.has_segments()) return std::nullopt;
    auto points = find_operating_points(m, options);
    m = select_operating_points(std::move(m), points);
    return points;
}

std::string operating_points_summary(const OperatingPoints& points) {
    return fmt::format("operating points: found automatically (the log has no segment column): {} steady window{}, "
                       "{} of {} rows dropped as transient (moving-sum test on {}, {} rows a side, false-alarm "
                       "probability {}, windows of at least {} rows)",
                       points.windows.size(), points.windows.size() == 1 ? "" : "s", points.transient_rows, points.rows,
                       fmt::join(points.channels, ", "), points.bandwidth, points.false_alarm, points.min_rows);
}

}  // namespace mhb::pmsm

#include "problems/pmsm/diagnosis/design.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "problems/pmsm/diagnosis/segments.hpp"
#include "problems/pmsm/diagnosis/verdict.hpp"

namespace mhb::pmsm {

using evidence::clear_above;

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

Measurement design_of(const Measurement& data) {
    Measurement d = data;
    // Without segments the operating points are unknown: the samples themselves are the design.
    if (!data.has_segments()) return d;
    for (const auto& r : segment_ranges(data)) {
        for (auto* column : {&d.i_d, &d.i_q, &d.omega_e}) column->segment(r.first, r.rows).setConstant(column->segment(r.first, r.rows).mean());
        for (auto* column : {&d.temp_winding, &d.temp_magnet}) {
            if (!*column || r.rows < 2) continue;
            auto block = (*column)->segment(r.first, r.rows);
            const Eigen::ArrayXd x = Eigen::ArrayXd::LinSpaced(r.rows, 0.0, static_cast<double>(r.rows - 1));
            const double xm = x.mean(), ym = block.mean();
            const double slope = ((x - xm) * (block.array() - ym)).sum() / (x - xm).square().sum();
            block = (ym + slope * (x - xm)).matrix();
        }
    }
    return d;
}

Measurement with_point(const Measurement& design, const OperatingPoint& p) {
    Measurement d = design;
    const Eigen::Index n = design.size(), m = design.theta_e ? 72 : 2;
    auto grow = [&](Eigen::VectorXd& v, double value) {
        v.conservativeResize(n + m);
        v.tail(m).setConstant(value);
    };
    grow(d.i_d, p.i_d);
    grow(d.i_q, p.i_q);
    grow(d.omega_e, p.omega);
    grow(d.u_d, 0.0);
    grow(d.u_q, 0.0);
    if (d.t) grow(*d.t, 0.0);
    if (d.temp_winding) grow(*d.temp_winding, p.temp_winding);
    if (d.temp_magnet) grow(*d.temp_magnet, p.temp_magnet);
    if (d.theta_e) {
        grow(*d.theta_e, 0.0);
        for (Eigen::Index k = 0; k < m; ++k)
            (*d.theta_e)[n + k] = wrap_angle(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(m));
    }
    if (d.has_segments()) {
        d.segment.conservativeResize(n + m);
        d.segment.tail(m).setConstant(static_cast<int>(d.segment_labels.size()));
        d.segment_labels.push_back("hypothetical");
    }
    return d;
}

Measurement with_angle(const Measurement& design) {
    Measurement d = design;
    d.theta_e = Eigen::VectorXd(d.size());
    for (const auto& r : segment_ranges(d))
        for (Eigen::Index k = 0; k < r.rows; ++k)
            (*d.theta_e)[r.first + k] = wrap_angle(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(r.rows));
    return d;
}

double unique_fraction(const Eigen::MatrixXd& others, const Eigen::VectorXd& column) {
    const double norm = column.norm();
    if (!(norm > 0.0)) return nan;
    if (others.cols() == 0) return 1.0;
    Eigen::MatrixXd scaled = others;
    for (Eigen::Index j = 0; j < scaled.cols(); ++j) {
        const double s = scaled.col(j).norm();
        if (s > 0.0) scaled.col(j) /= s;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(scaled);
    qr.setThreshold(1e-10);
    const Eigen::Index rank = qr.rank();
    Eigen::VectorXd coefficients = qr.householderQ().adjoint() * column;
    coefficients.tail(coefficients.size() - rank).setZero();
    const Eigen::VectorXd projected = qr.householderQ() * coefficients;
    return (column - projected).norm() / norm;
}

std::vector<double> design_unique_fractions(const Measurement& design, const ModelSpec& spec, const Eigen::VectorXd& model_values,
                                            const std::string& effect, const std::string& rival) {
    ModelSpec full = spec.with(effect);
    if (!rival.empty()) full = full.with(rival);
    const auto model = make_model(full, design);
    Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    values.head(model_values.size()) = model_values;
    const auto free = free_parameters(full);
    const auto base_count = static_cast<Eigen::Index>(free_parameters(spec).size());
    const auto effect_count = static_cast<Eigen::Index>(free_parameters(spec.with(effect)).size()) - base_count;
    std::vector<Eigen::Index> columns, own;
    for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(free.size()); ++j) {
        if (!free[static_cast<std::size_t>(j)]) continue;
        columns.push_back(j);
        const bool is_effect = j >= base_count && j < base_count + effect_count;
        if (is_effect) own.push_back(static_cast<Eigen::Index>(columns.size()) - 1);
    }
    const Eigen::MatrixXd jacobian = prediction_jacobian(*model, values, columns);
    std::vector<Eigen::Index> others;
    for (Eigen::Index c = 0; c < jacobian.cols(); ++c)
        if (std::find(own.begin(), own.end(), c) == own.end()) others.push_back(c);
    Eigen::MatrixXd other_columns(jacobian.rows(), static_cast<Eigen::Index>(others.size()));
    for (std::size_t c = 0; c < others.size(); ++c) other_columns.col(static_cast<Eigen::Index>(c)) = jacobian.col(others[c]);
    std::vector<double> out;
    for (const auto c : own) out.push_back(unique_fraction(other_columns, jacobian.col(c)));
    return out;
}

double most_distinct(const std::vector<double>& fractions) {
    double best = nan;
    for (double f : fractions)
        if (std::isfinite(f) && !(f <= best)) best = f;
    return best;
}

std::vector<Proposal> experiment_proposals(const Measurement& data, const std::vector<SegmentConditions>& segments) {
    std::vector<Proposal> out;
    if (segments.empty()) return out;
    const auto fastest = *std::max_element(segments.begin(), segments.end(),
                                           [](const auto& a, const auto& b) { return std::abs(a.omega) < std::abs(b.omega); });
    double largest_current = 0.0, lowest_i_d = 0.0;
    for (const auto& s : segments) {
        largest_current = std::max(largest_current, std::hypot(s.i_d, s.i_q));
        lowest_i_d = std::min(lowest_i_d, s.i_d);
    }
    if (!(largest_current > 0.0)) largest_current = 1.0;
    const OperatingPoint base{fastest.omega, fastest.i_d, fastest.i_q, fastest.temp_winding.value_or(reference_temperature),
                              fastest.temp_magnet.value_or(reference_temperature)};
    auto add = [&](std::string name, OperatingPoint p) {
        // Currents that are zero up to the noise of the segment means read as zero.
        for (double* i : {&p.i_d, &p.i_q})
            if (std::abs(*i) < 1e-3 * largest_current) *i = 0.0;
        const std::string where = fmt::format("omega_e = {:.3g} rad/s, i_d = {:.3g} A, i_q = {:.3g} A", p.omega, p.i_d, p.i_q);
        out.push_back({{std::move(name), where, 0.0}, [p](const Measurement& d) { return with_point(d, p); }});
    };
    OperatingPoint p = base;
    p.omega = base.omega / 2.0;
    add("another speed", p);
    p = base;
    p.omega = -base.omega;
    p.i_q = -base.i_q;
    add("the other direction", p);
    p = base;
    p.i_d = lowest_i_d - 0.5 * largest_current;
    add("another d-axis current", p);
    p = base;
    p.i_q = base.i_q + (base.i_q < 0.0 ? -0.5 : 0.5) * largest_current;
    add("another load", p);
    if (data.temp_winding || data.temp_magnet) {
        p = base;
        p.temp_winding += 30.0;
        p.temp_magnet += 30.0;
        out.push_back({{"a temperature change", fmt::format("the fastest point again 30 K warmer (omega_e = {:.3g} rad/s)", p.omega), 0.0},
                       [p](const Measurement& d) { return with_point(d, p); }});
    }
    if (!data.theta_e)
        out.push_back({{"logging theta_e", "the controller's electrical angle with every sample", 0.0},
                       [](const Measurement& d) { return with_angle(d); }});
    return out;
}

std::vector<Experiment> revealing_experiments(const Measurement& design, const std::vector<Proposal>& proposals, const ModelSpec& spec,
                                              const Eigen::VectorXd& model_values, const std::string& effect,
                                              const std::string& rival) {
    auto clarity = [&](const Measurement& d) {
        double u = most_distinct(design_unique_fractions(d, spec, model_values, effect, rival));
        if (!rival.empty()) u = std::min(u, most_distinct(design_unique_fractions(d, spec, model_values, rival, effect)));
        return u;
    };
    std::vector<Experiment> out;
    for (const auto& p : proposals) {
        Experiment e = p.experiment;
        e.unique_after = clarity(p.apply(design));
        if (e.unique_after >= clear_above) out.push_back(e);
    }
    if (out.empty() && proposals.size() > 1) {
        Measurement all = design;
        std::string names;
        for (const auto& p : proposals) {
            all = p.apply(all);
            names += (names.empty() ? "" : ", ") + p.experiment.name;
        }
        const double u = clarity(all);
        if (u >= clear_above) out.push_back({"all of these together", names, u});
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.unique_after > b.unique_after; });
    return out;
}

}  // namespace mhb::pmsm

#include "problems/pmsm/machine/power_law_flux_fit.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>

#include <Eigen/Dense>

namespace mhb::pmsm {
namespace {

constexpr int magnet_index = 9;  // the one parameter that is not kept positive through its logarithm
using Coordinates = Eigen::Matrix<double, PowerLawSaturation::count, 1>;
// Residuals at the coordinates, or nothing where the model is inadmissible there.
using Residuals = std::function<std::optional<Eigen::VectorXd>(const Coordinates&)>;

PowerLawSaturation parameters_at(const Coordinates& theta, double base_current, double base_flux) {
    std::array<double, PowerLawSaturation::count> x{};
    for (int k = 0; k < PowerLawSaturation::count; ++k) x[k] = k == magnet_index ? theta[k] : std::exp(theta[k]);
    return PowerLawSaturation::from_values(x, base_current, base_flux);
}

Coordinates coordinates_of(const PowerLawSaturation& p) {
    const auto x = p.values();
    Coordinates theta;
    for (int k = 0; k < PowerLawSaturation::count; ++k) theta[k] = k == magnet_index ? x[k] : std::log(x[k]);
    return theta;
}

bool convex_at(const PowerLawFlux& model, Complex psi) {
    const auto h = model.inverse_inductance(psi);
    return h[0] > 0.0 && h[0] * h[3] - h[1] * h[2] > 0.0;
}

// Levenberg-Marquardt with a forward-difference Jacobian and Marquardt's diagonal scaling.
Coordinates least_squares(const Residuals& residuals, Coordinates theta, int iterations, int& used) {
    auto r = residuals(theta);
    if (!r) throw std::invalid_argument("flux model fit: the starting point is not admissible");
    double cost = r->squaredNorm(), lambda = 1e-3;
    const int n = PowerLawSaturation::count;
    for (int iteration = 0; iteration < iterations; ++iteration) {
        ++used;
        Eigen::MatrixXd jacobian(r->size(), n);
        for (int k = 0; k < n; ++k) {
            Coordinates moved = theta;
            const double h = 1e-7 * std::max(1.0, std::abs(theta[k]));
            moved[k] += h;
            const auto rk = residuals(moved);
            jacobian.col(k) = rk ? Eigen::VectorXd((*rk - *r) / h) : Eigen::VectorXd::Zero(r->size());
        }
        const Eigen::MatrixXd normal = jacobian.transpose() * jacobian;
        const Eigen::VectorXd gradient = jacobian.transpose() * *r;
        bool accepted = false;
        while (lambda < 1e12) {
            Eigen::MatrixXd damped = normal;
            damped.diagonal() += lambda * (normal.diagonal().array() + 1e-12).matrix();
            const Coordinates step = damped.ldlt().solve(-gradient);
            const Coordinates candidate = theta + step;
            const auto rc = residuals(candidate);
            if (rc && rc->squaredNorm() < cost) {
                const double decrease = cost - rc->squaredNorm();
                theta = candidate;
                r = rc;
                cost = r->squaredNorm();
                lambda = std::max(lambda / 3.0, 1e-12);
                accepted = true;
                if (decrease < 1e-14 * cost || step.norm() < 1e-12) return theta;
                break;
            }
            lambda *= 4.0;
        }
        if (!accepted) return theta;
    }
    return theta;
}

// A start inside the basin of a saturating machine: the unsaturated inductances from the points at
// small current, mild saturation, and the magnet's Norton flux a little above the no-load flux.
PowerLawSaturation starting_parameters(const FluxPoints& points, double base_current, double base_flux) {
    double sdd = 0, sd = 0, sqq = 0, sq = 0, magnet = 0, nearest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < points.current.size(); ++k)
        if (std::abs(points.current[k]) < nearest) {
            nearest = std::abs(points.current[k]);
            magnet = points.flux[k].real();
        }
    for (std::size_t k = 0; k < points.current.size(); ++k) {
        const Complex i = points.current[k] / base_current, psi = points.flux[k] / base_flux;
        if (std::abs(i) > 0.3) continue;
        sdd += i.real() * i.real();
        sd += i.real() * (psi.real() - magnet / base_flux);
        sqq += i.imag() * i.imag();
        sq += i.imag() * psi.imag();
    }
    const double ld = sdd > 0 && sd > 0 ? sd / sdd : 1.0, lq = sqq > 0 && sq > 0 ? sq / sqq : 1.0;
    PowerLawSaturation p;
    p.base_current = base_current;
    p.base_flux = base_flux;
    p.d0 = 0.5 / ld;
    p.dd = 0.2;
    p.s = 4.0;
    p.q0 = 1.0 / lq;
    p.qq = 0.2;
    p.t = 2.0;
    p.dq = 0.1;
    p.u = 1.0;
    p.v = 1.0;
    p.magnet = 1.1 * magnet / base_flux;
    p.bridge = 0.5 / ld;
    p.bridge_saturation = 1.0;
    p.w = 2.0;
    p.bridge_q = 0.1;
    return p;
}

}  // namespace

FluxPoints flux_points(const FluxMap& map) {
    FluxPoints points;
    for (double d : map.i_d_grid())
        for (double q : map.i_q_grid()) {
            points.current.emplace_back(d, q);
            points.flux.push_back(map.flux({d, q}, map.nominal_psi_f()));
        }
    return points;
}

FluxModelFit fit_flux_model(const FluxPoints& points, const FluxFitOptions& options) {
    const std::size_t n = points.current.size();
    if (n != points.flux.size() || n < static_cast<std::size_t>(PowerLawSaturation::count))
        throw std::invalid_argument("flux model fit: needs at least as many (current, flux) points as parameters");
    double base_current = options.base_current, base_flux = options.base_flux;
    double lo_d = std::numeric_limits<double>::infinity(), hi_d = -lo_d, lo_q = lo_d, hi_q = -lo_d;
    for (std::size_t k = 0; k < n; ++k) {
        if (options.base_current <= 0.0)
            base_current = std::max({base_current, std::abs(points.current[k].real()), std::abs(points.current[k].imag())});
        if (options.base_flux <= 0.0)
            base_flux = std::max({base_flux, std::abs(points.flux[k].real()), std::abs(points.flux[k].imag())});
        lo_d = std::min(lo_d, points.flux[k].real());
        hi_d = std::max(hi_d, points.flux[k].real());
        lo_q = std::min(lo_q, points.flux[k].imag());
        hi_q = std::max(hi_q, points.flux[k].imag());
    }
    FluxModelFit fit;
    fit.span_d = hi_d - lo_d;
    fit.span_q = hi_q - lo_q;
    if (!(base_current > 0.0) || !(base_flux > 0.0) || !(fit.span_d > 0.0) || !(fit.span_q > 0.0))
        throw std::invalid_argument("flux model fit: the points need nonzero currents and fluxes that vary on both axes");

    auto admissible_model = [&](const Coordinates& theta) -> std::optional<PowerLawFlux> {
        const auto p = parameters_at(theta, base_current, base_flux);
        if (!p.inadmissible_reason().empty()) return std::nullopt;
        try {
            return PowerLawFlux(p);
        } catch (const std::exception&) {
            return std::nullopt;
        }
    };
    const Residuals current_residuals = [&](const Coordinates& theta) -> std::optional<Eigen::VectorXd> {
        const auto model = admissible_model(theta);
        if (!model) return std::nullopt;
        Eigen::VectorXd r(2 * n);
        for (std::size_t k = 0; k < n; ++k) {
            if (!convex_at(*model, points.flux[k])) return std::nullopt;
            const Complex e = (model->current_of_flux(points.flux[k]) - points.current[k]) / base_current;
            r[2 * k] = e.real();
            r[2 * k + 1] = e.imag();
        }
        return r.allFinite() ? std::optional(r) : std::nullopt;
    };
    const Residuals flux_residuals = [&](const Coordinates& theta) -> std::optional<Eigen::VectorXd> {
        const auto model = admissible_model(theta);
        if (!model) return std::nullopt;
        Eigen::VectorXd r(2 * n);
        try {
            for (std::size_t k = 0; k < n; ++k) {
                const Complex psi = model->flux_of_current(points.current[k]);
                if (!convex_at(*model, psi)) return std::nullopt;
                r[2 * k] = (psi.real() - points.flux[k].real()) / fit.span_d;
                r[2 * k + 1] = (psi.imag() - points.flux[k].imag()) / fit.span_q;
            }
        } catch (const std::runtime_error&) {
            return std::nullopt;
        }
        return r.allFinite() ? std::optional(r) : std::nullopt;
    };

    Coordinates theta = coordinates_of(starting_parameters(points, base_current, base_flux));
    theta = least_squares(current_residuals, theta, options.iterations, fit.iterations);
    theta = least_squares(flux_residuals, theta, options.iterations, fit.iterations);

    fit.parameters = parameters_at(theta, base_current, base_flux);
    const PowerLawFlux model(fit.parameters);
    double sum_d = 0.0, sum_q = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
        const Complex e = model.flux_of_current(points.current[k]) - points.flux[k];
        sum_d += e.real() * e.real();
        sum_q += e.imag() * e.imag();
        fit.max_error_d = std::max(fit.max_error_d, std::abs(e.real()));
        fit.max_error_q = std::max(fit.max_error_q, std::abs(e.imag()));
    }
    fit.rms_d = std::sqrt(sum_d / static_cast<double>(n));
    fit.rms_q = std::sqrt(sum_q / static_cast<double>(n));
    return fit;
}

FluxModelFit fit_flux_model(const FluxMap& map, const FluxFitOptions& options) {
    return fit_flux_model(flux_points(map), options);
}

}  // namespace mhb::pmsm

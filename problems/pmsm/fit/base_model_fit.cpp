#include "problems/pmsm/fit/base_model_fit.hpp"

#include <cmath>
#include <stdexcept>

#include "framework/input_error.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"

namespace mhb::pmsm {

Fitness parse_fitness(const std::string& name) {
    if (name == "mse") return Fitness::MeanSquared;
    if (name == "noise_weighted") return Fitness::NoiseWeighted;
    throw ParameterError("fitness", "expects mse or noise_weighted (got " + name + ")");
}

const char* to_string(Fitness fitness) { return fitness == Fitness::MeanSquared ? "mse" : "noise_weighted"; }

void base_regression(const Measurement& m, Eigen::MatrixXd& phi, Eigen::VectorXd& y) {
    const Eigen::Index n = m.size();
    phi.setZero(2 * n, 4);
    y.resize(2 * n);
    phi.block(0, 0, n, 1) = m.i_d;
    phi.block(0, 2, n, 1) = -(m.omega_e.array() * m.i_q.array()).matrix();
    phi.block(n, 0, n, 1) = m.i_q;
    phi.block(n, 1, n, 1) = (m.omega_e.array() * m.i_d.array()).matrix();
    phi.block(n, 3, n, 1) = m.omega_e;
    y.head(n) = m.u_d;
    y.tail(n) = m.u_q;
}

BaseModelFit fit_base_model(const Measurement& m, Fitness fitness, CovarianceMethod method) {
    const Eigen::Index n = m.size();
    if (n < 3) throw std::invalid_argument("fitting the base model needs at least 3 samples");
    Eigen::MatrixXd phi;
    Eigen::VectorXd y;
    base_regression(m, phi, y);

    BaseModelFit fit;
    fit.fitness = fitness;
    fit.samples = n;
    const LeastSquares plain = solve_least_squares(phi, y);
    const Eigen::VectorXd residual = y - phi * plain.solution;
    for (int a = 0; a < 2; ++a) fit.axis_noise[a] = std::sqrt(residual.segment(a * n, n).squaredNorm() / static_cast<double>(n));

    if (fitness == Fitness::NoiseWeighted) {
        // Noise-free data would give zero variances: floor each at a part in 1e9 of the axis' signal.
        for (int a = 0; a < 2; ++a) {
            const double signal = std::sqrt(y.segment(a * n, n).squaredNorm() / static_cast<double>(n));
            const double sigma = std::max(fit.axis_noise[a], 1e-9 * signal + 1e-300);
            fit.axis_weight[a] = 1.0 / (sigma * sigma);
            phi.middleRows(a * n, n) *= std::sqrt(fit.axis_weight[a]);
            y.segment(a * n, n) *= std::sqrt(fit.axis_weight[a]);
        }
        fit.least_squares = solve_least_squares(phi, y);
    } else {
        fit.least_squares = plain;
    }
    fit.in_bounds = box_least_squares(fit.least_squares, base_parameter_bounds());

    RowLayout layout;
    layout.samples = n;
    layout.axes = 2;
    if (m.has_segments()) layout.block = m.segment;
    fit.uncertainty = parameter_uncertainty(phi, y, fit.least_squares.solution, layout, method);
    return fit;
}

}  // namespace mhb::pmsm

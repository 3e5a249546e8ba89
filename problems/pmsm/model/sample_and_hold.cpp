#include "problems/pmsm/model/sample_and_hold.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <unsupported/Eigen/MatrixFunctions>

namespace mhb::pmsm {

std::complex<double> held_voltage(const Eigen::Vector4d& base, double omega, std::complex<double> current, double period) {
    const double rs = base[0], ld = base[1], lq = base[2], psi_f = base[3];
    // State (psi_d, psi_q, v_d, v_q, 1) over one period: the rotor-frame flux under
    // psi' = v - Rs L^-1 (psi - psi_f e_d) - omega J psi, and the held stator-frame voltage seen from
    // the rotor, v' = -omega J v (J turns by +90 degrees).
    Eigen::Matrix<double, 5, 5> a = Eigen::Matrix<double, 5, 5>::Zero();
    a(0, 0) = -rs / ld;
    a(0, 1) = omega;
    a(0, 2) = 1.0;
    a(0, 4) = rs / ld * psi_f;
    a(1, 0) = -omega;
    a(1, 1) = -rs / lq;
    a(1, 3) = 1.0;
    a(2, 3) = omega;
    a(3, 2) = -omega;
    const Eigen::Matrix<double, 5, 5> e = (a * period).exp();
    // Steady state: the flux at the period's end, in the rotor frame, is the one at its start.
    const Eigen::Vector2d psi{ld * current.real() + psi_f, lq * current.imag()};
    const Eigen::Vector2d rhs = psi - e.block<2, 2>(0, 0) * psi - e.block<2, 1>(0, 4);
    const Eigen::Vector2d v = e.block<2, 2>(0, 2).partialPivLu().solve(rhs);
    // v is the held voltage in the rotor frame at the period's start; the controller computed it one
    // period earlier and turned it by 1.5 omega T, so its own frame lies omega T / 2 behind.
    return std::complex<double>(v[0], v[1]) * std::polar(1.0, -0.5 * omega * period);
}

namespace {

// How far the base model's least-squares fit moves from `base` when the voltages of every `step`-th
// row of `data` are the held ones instead of the continuous model's at `base`: the fit of the
// differences (the model is linear in the base parameters). Parameters the rows do not determine
// (psi_f without speed) do not move.
Eigen::Vector4d refit_shift(const Measurement& data, const Eigen::Vector4d& base, double period, Eigen::Index step) {
    Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
    Eigen::Vector4d projected = Eigen::Vector4d::Zero();
    for (Eigen::Index k = 0; k < data.size(); k += step) {
        const double w = data.omega_e[k];
        const std::complex<double> i{data.i_d[k], data.i_q[k]};
        // The base model's columns (Rs, Ld, Lq, psi_f) on each axis.
        const Eigen::Vector4d on_d{i.real(), 0.0, -w * i.imag(), 0.0}, on_q{i.imag(), w * i.real(), 0.0, w};
        const std::complex<double> difference = held_voltage(base, w, i, period) - std::complex<double>(on_d.dot(base), on_q.dot(base));
        normal += on_d * on_d.transpose() + on_q * on_q.transpose();
        projected += on_d * difference.real() + on_q * difference.imag();
    }
    return normal.completeOrthogonalDecomposition().solve(projected);
}

}  // namespace

Eigen::Vector4d sample_and_hold_bias(const Measurement& data, const Eigen::Vector4d& base, double period, Eigen::Index max_rows) {
    if (!(period > 0.0) || data.size() == 0) return Eigen::Vector4d::Zero();
    const Eigen::Index step = std::max<Eigen::Index>(1, (data.size() + max_rows - 1) / std::max<Eigen::Index>(max_rows, 1));
    // The fitted values are the machine's plus the bias; the bias is evaluated at the machine's.
    const Eigen::Vector4d first = refit_shift(data, base, period, step);
    return refit_shift(data, base - first, period, step);
}

}  // namespace mhb::pmsm

#include "problems/pmsm/simulation/thermal_network.hpp"

#include <cmath>

namespace mhb::pmsm {
namespace {

// exp(M) of a small matrix by scaling and squaring a Taylor series (the thermal network's 3 x 3
// augmented matrix, whose norm is known only at run time).
Eigen::Matrix3d matrix_exponential(const Eigen::Matrix3d& m) {
    const double norm = m.cwiseAbs().rowwise().sum().maxCoeff();
    int squarings = 0;
    while (std::ldexp(norm, -squarings) > 0.5) ++squarings;
    const Eigen::Matrix3d a = m * std::ldexp(1.0, -squarings);
    Eigen::Matrix3d sum = Eigen::Matrix3d::Identity(), term = Eigen::Matrix3d::Identity();
    for (int k = 1; k <= 16; ++k) {
        term = term * a / static_cast<double>(k);
        sum += term;
    }
    for (int k = 0; k < squarings; ++k) sum = sum * sum;
    return sum;
}

}  // namespace

HeatedWindingAndMagnet::HeatedWindingAndMagnet(const ThermalNetwork& n, double period) : network_(n) {
    rise_ = {n.initial_winding - n.ambient, n.initial_magnet - n.ambient};
    if (!n.enabled) return;
    Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
    m(0, 0) = -(1.0 / n.winding_to_ambient + 1.0 / n.winding_to_magnet) / n.winding_capacity;
    m(0, 1) = 1.0 / (n.winding_to_magnet * n.winding_capacity);
    m(1, 0) = 1.0 / (n.winding_to_magnet * n.magnet_capacity);
    m(1, 1) = -(1.0 / n.magnet_to_ambient + 1.0 / n.winding_to_magnet) / n.magnet_capacity;
    m(0, 2) = 1.0 / n.winding_capacity;
    const Eigen::Matrix3d e = matrix_exponential(m * period);
    transition_ = e.topLeftCorner<2, 2>();
    input_ = e.topRightCorner<2, 1>();
}

}  // namespace mhb::pmsm

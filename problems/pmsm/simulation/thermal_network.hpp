#pragma once
// The device plant's winding and magnet temperatures: a two-node thermal network heated by the
// copper and iron losses, advanced exactly over each control period.
#include <Eigen/Core>

#include "problems/pmsm/simulation/device_settings.hpp"

namespace mhb::pmsm {

// The two-node network in temperature rises over the ambient, theta = T - T_amb:
//   C_w dtheta_w/dt = P - theta_w / R_wa - (theta_w - theta_m) / R_wm
//   C_m dtheta_m/dt = (theta_w - theta_m) / R_wm - theta_m / R_ma
// discretised exactly for a loss P held over one control period.
class HeatedWindingAndMagnet {
public:
    HeatedWindingAndMagnet(const ThermalNetwork& n, double period);

    void advance(double loss) {
        if (network_.enabled) rise_ = transition_ * rise_ + input_ * loss;
    }
    double winding() const { return network_.ambient + rise_[0]; }
    double magnet() const { return network_.ambient + rise_[1]; }

private:
    ThermalNetwork network_;
    Eigen::Vector2d rise_;
    Eigen::Matrix2d transition_ = Eigen::Matrix2d::Identity();
    Eigen::Vector2d input_ = Eigen::Vector2d::Zero();
};

}  // namespace mhb::pmsm

#include "problems/pmsm/simulation/field_oriented_controller.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "problems/pmsm/simulation/drive_configuration.hpp"

namespace mhb::pmsm {

// Tuning from the nominal motor: IMC current loops (closed loop first order at the bandwidth), speed
// PI placing a double pole at the speed bandwidth.
FieldOrientedController::FieldOrientedController(const MotorParameters& nominal, const Mechanics& mechanics,
                                                 const DriveControl& control)
    : nominal_(nominal), ts_(control.control_period), current_limit_(control.current_limit),
      position_gain_(control.position_gain) {
    const double alpha_c = 2.0 * std::numbers::pi * control.current_bandwidth;
    kp_d_ = alpha_c * nominal.ld;
    kp_q_ = alpha_c * nominal.lq;
    ki_i_ = alpha_c * nominal.rs;
    const double alpha_s = 2.0 * std::numbers::pi * control.speed_bandwidth;
    const double torque_constant = 1.5 * nominal.pole_pairs * nominal.psi_f;
    const double inertia = mechanics.total_inertia();
    kp_w_ = 2.0 * alpha_s * inertia / torque_constant;
    ki_w_ = alpha_s * alpha_s * inertia / torque_constant;
    voltage_limit_ = control.dc_voltage / std::numbers::sqrt3;
}

double FieldOrientedController::estimate_speed(double measured_angle, double initial_speed) {
    const double omega = first_estimate_ ? initial_speed : wrap_angle(measured_angle - previous_angle_) / ts_;
    previous_angle_ = measured_angle;
    first_estimate_ = false;
    return omega;
}

Complex FieldOrientedController::update(const Segment& segment, Complex measured_current, double measured_speed) {
    const double p = nominal_.pole_pairs;
    const double speed_ref_m = segment.speed_rpm * 2.0 * std::numbers::pi / 60.0;
    // Position (optional) and speed loops give the q-current reference.
    double speed_ref = speed_ref_m;
    if (position_gain_ > 0) {
        position_error_ += (speed_ref_m - measured_speed / p) * ts_;
        speed_ref += position_gain_ * position_error_;
    }
    const double speed_error = speed_ref - measured_speed / p;
    const double i_d_ref = std::clamp(segment.i_d, -current_limit_, current_limit_);
    const double i_q_max = std::sqrt(std::max(current_limit_ * current_limit_ - i_d_ref * i_d_ref, 0.0));
    double i_q_ref = kp_w_ * speed_error + integral_w_;
    if (std::abs(i_q_ref) > i_q_max) {
        i_q_ref = std::copysign(i_q_max, i_q_ref);
        if (speed_error * i_q_ref < 0) integral_w_ += ki_w_ * ts_ * speed_error;  // only unwinding
    } else {
        integral_w_ += ki_w_ * ts_ * speed_error;
    }

    // Current loops with decoupling; integrate only while the voltage is not limited.
    const double e_d = i_d_ref - measured_current.real(), e_q = i_q_ref - measured_current.imag();
    Complex u_ref{kp_d_ * e_d + integral_d_ - measured_speed * nominal_.lq * measured_current.imag(),
                  kp_q_ * e_q + integral_q_ + measured_speed * (nominal_.ld * measured_current.real() + nominal_.psi_f)};
    if (std::abs(u_ref) > voltage_limit_) {
        u_ref *= voltage_limit_ / std::abs(u_ref);
    } else {
        integral_d_ += ki_i_ * ts_ * e_d;
        integral_q_ += ki_i_ * ts_ * e_q;
    }
    return u_ref;
}

}  // namespace mhb::pmsm

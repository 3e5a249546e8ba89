#pragma once
// The drive's controller, shared by both plants (the averaged dq plant and the device plant): current
// PI loops with decoupling in the controller's own frame, a speed PI loop on the encoder's speed
// estimate and an optional position loop, all tuned from the nominal motor. It sees only what a real
// controller sees (measured currents, measured angle), so a plant's imperfections reach the loops the
// way they do on a drive. docs/pmsm.md gives the tuning.
#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {

struct Mechanics;
struct DriveControl;
struct Segment;

class FieldOrientedController {
public:
    FieldOrientedController(const MotorParameters& nominal, const Mechanics& mechanics, const DriveControl& control);

    // Electrical speed from the change of the measured angle over one control period, as drives
    // estimate it; the very first call has no previous angle and returns `initial_speed`.
    double estimate_speed(double measured_angle, double initial_speed);

    // One control period: the segment's references, the measured current in the controller's frame
    // and the measured electrical speed give the voltage reference in the controller's frame.
    Complex update(const Segment& segment, Complex measured_current, double measured_speed);

    double control_period() const { return ts_; }

private:
    MotorParameters nominal_;
    double ts_, current_limit_, position_gain_;
    double kp_d_, kp_q_, ki_i_, kp_w_, ki_w_, voltage_limit_;
    double integral_d_ = 0.0, integral_q_ = 0.0, integral_w_ = 0.0, position_error_ = 0.0;
    double previous_angle_ = 0.0;
    bool first_estimate_ = true;
};

}  // namespace mhb::pmsm

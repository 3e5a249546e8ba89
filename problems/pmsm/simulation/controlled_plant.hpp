#pragma once
// What the closed-loop drive (drive_simulator.cpp) needs from a plant: its sensors at a control
// instant, one control period of its actuator and machine, and what it logs beside the controller's
// signals. Two plants implement it: the averaged dq plant with the effect library's hooks
// (drive_simulator.cpp) and the device plant (device_plant.cpp); the controller and the logging are
// the same for both.
#include <cstdint>

#include "framework/random.hpp"
#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {

struct Segment;

// What the drive's sensors give the controller at one control instant.
struct SensorReading {
    Complex current;           // measured phase currents as an alpha-beta vector (A)
    double angle = 0.0;        // measured electrical angle (rad): the controller's frame
    double shaft_angle = 0.0;  // measured mechanical angle of the shaft (rad, in [-pi, pi)), what an absolute encoder logs
    double true_speed = 0.0;   // electrical speed (rad/s); used only before the encoder has a previous angle
};

struct Temperatures {
    double winding = 0.0;  // °C
    double magnet = 0.0;   // °C
};

class ControlledPlant {
public:
    virtual ~ControlledPlant() = default;
    // The sensors at control instant t (noise drawn from rng).
    virtual SensorReading sense(double t, Rng& rng) = 0;
    // One control period from t: the controller's voltage reference in its frame, with the measured
    // angle and speed it was computed from.
    virtual void run_control_period(double t, Complex voltage_reference, const SensorReading& reading,
                                    double measured_speed, const Segment& segment) = 0;
    // Winding and magnet temperatures at t, before logging noise.
    virtual Temperatures temperatures(double t) const = 0;
    // A constant error of the logging channels' voltages (ADC offset), added to the logged u_d, u_q.
    virtual Complex logged_voltage_offset() const { return {}; }
    virtual std::int64_t integration_steps() const = 0;
};

}  // namespace mhb::pmsm

#pragma once
// What a simulated drive is made of: motor, mechanics, control and logging settings, sensor noise,
// temperature profiles and the segments of its profile, and what a simulation returns. Both plants,
// the controller and the simulator read these; none of them owns them.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/machine/machine.hpp"
#include "problems/pmsm/simulation/device_settings.hpp"

namespace mhb::pmsm {

struct Mechanics {
    double motor_inertia = 1e-4;  // kg m^2
    double load_inertia = 1.07;   // kg m^2 at the reducer output
    double gear_ratio = 100.0;    // motor turns per output turn
    double viscous_friction = 0.0;  // N m s/rad at the motor shaft
    // Inertia seen by the motor: J_m + J_L / N^2.
    double total_inertia() const { return motor_inertia + load_inertia / (gear_ratio * gear_ratio); }
};

struct DriveControl {
    double dc_voltage = 28.0;           // V; the voltage reference is limited to V_dc / sqrt 3
    double control_period = 100e-6;     // s, current and speed loops
    double integration_step = 10e-6;    // s, RK4 step of the plant; divides the control period
    double current_bandwidth = 500.0;   // Hz, current-loop closed-loop bandwidth
    double speed_bandwidth = 10.0;      // Hz, speed loop (double closed-loop pole)
    double position_gain = 0.0;         // 1/s, position loop around the speed loop (0: off)
    double current_limit = 0.5;         // A, magnitude limit of the current reference
};

struct Logging {
    double period = 0.4e-3;       // s, a multiple of the control period
    double filter_cutoff = 0.0;   // Hz, first-order low-pass on the logged signals (0: none)
    bool theta = true;            // log the controller's angle theta_e
    bool shaft_angle = false;     // log the encoder's mechanical angle theta_m
    bool time = true;             // log t
    bool temperatures = false;    // log temp_winding and temp_magnet
    // Log each segment's settling too, as a bench logs everything: a raw log of steps, ramps and
    // steady stretches. Its rows draw their noise from a stream of their own, so the steady rows
    // are those of the same drive logged without transients, bit for bit.
    bool transients = false;
    bool segment = true;          // write the segment column (false: a log without operating points)
};

// Standard deviations of white sensor noise, entering where a real drive's would.
struct SensorNoise {
    double current = 0.0;      // A, each of the two phase-current sensors (enters the current loop)
    double speed = 0.0;        // rad/s electrical, on the measured speed (enters the speed loop)
    double voltage = 0.0;      // V, added to the logged voltage references (logging only)
    double temperature = 0.0;  // K, added to the logged temperatures
};

// Piecewise-linear temperature over simulation time, held constant beyond the first and last points.
struct TemperatureProfile {
    std::vector<std::pair<double, double>> points{{0.0, reference_temperature}};  // (s, °C), ascending t
    double at(double t) const;
};

struct Segment {
    std::string label;         // written to the segment column
    double speed_rpm = 0.0;    // speed reference at the motor shaft, r/min (signed)
    double load_torque = 0.0;  // N m at the motor shaft (signed, constant)
    double i_d = 0.0;          // A, d-axis current reference
    double settle = 0.0;       // s run before logging starts (not logged)
    std::int64_t samples = 0;  // logged samples, one per logging period
};

struct DriveSimulation {
    MotorParameters motor;
    Mechanics mechanics;
    DriveControl control;
    Logging logging;
    SensorNoise noise;
    std::uint64_t seed = 0;
    TemperatureProfile temp_winding, temp_magnet;
    std::vector<Segment> segments;
    std::vector<std::unique_ptr<Effect>> effects;  // averaged plant only
    std::optional<DeviceSettings> device;          // set: the device plant; the temperature profiles are unused
    std::filesystem::path base_directory;  // relative paths of effects (flux maps) resolve here
};

struct SegmentRows {
    std::string label;
    Eigen::Index first_row = 0;
    Eigen::Index rows = 0;
    double start_time = 0.0;  // s, when the segment's references were applied
    Eigen::Index settle_first_row = 0;  // first logged row of its settling (first_row unless transients are logged)
};

struct SimulationResult {
    Measurement data;
    std::vector<SegmentRows> segments;
    double simulated_time = 0.0;  // s
    std::int64_t integration_steps = 0;
};

// A copy of `base` (motor, mechanics, control, logging, noise, segments, base directory) on the device
// plant with `device` and noise seed `seed`: what a study varying device settings over seeds runs,
// one copy per simulation. `base`'s effects and temperature profiles are not copied (the device
// plant has its own).
DriveSimulation with_device(const DriveSimulation& base, const DeviceSettings& device, std::uint64_t seed);

// The flux linkage of the machine `spec` simulates: on the device plant its iron (linear, or saturating
// with stored energy); on the averaged plant the linear machine unless an effect replaces it (a
// saturation law, a measured map), at the plant's scale (its current limit and magnet flux).
std::unique_ptr<FluxModel> plant_flux_model(const DriveSimulation& spec);

// A positive integer ratio a / b (steps per control period, control periods per logged sample), or
// std::invalid_argument naming the two settings.
std::int64_t whole_ratio(double a, double b, const char* what);

}  // namespace mhb::pmsm

#pragma once
// Settings of the device plant (device_plant.cpp): each device of a real drive with its physical
// parameters. The defaults are ideal devices, so a default DeviceSettings is the clean drive; each
// imperfection is switched on by giving its parameter a non-ideal value. docs/pmsm.md, "The device
// plant", gives each device's equations and which library effect it corresponds to.
#include <cstdint>
#include <vector>

namespace mhb::pmsm {

// Two-level voltage-source inverter with centre-aligned (triangular-carrier) PWM.
struct InverterDevice {
    double pwm_frequency = 10e3;     // Hz; a whole number of carrier periods per control period
    double dead_time = 0.0;          // s, delay of every transistor turn-on edge
    double switch_drop = 0.0;        // V, conducting transistor (threshold voltage)
    double diode_drop = 0.0;         // V, conducting free-wheeling diode
    double switch_resistance = 0.0;  // Ω, conducting transistor's on-resistance
    double diode_resistance = 0.0;   // Ω, conducting diode's slope resistance
    bool delay_compensation = true;  // advance the modulation angle by 1.5 omega T_s
};

// Incremental encoder on the motor shaft.
struct EncoderDevice {
    std::int64_t lines = 0;  // lines per mechanical revolution (4 lines counts in quadrature); 0 = exact angle
    double offset = 0.0;     // rad electrical: measured angle minus the true d-axis angle
};

// One spatial harmonic of the magnet flux linked by each phase.
struct FluxHarmonic {
    int order = 5;           // odd, not a multiple of 3, >= 5
    double amplitude = 0.0;  // relative to psi_f
    double phase = 0.0;      // rad
};

struct RotorFluxDevice {
    std::vector<FluxHarmonic> harmonics;
    // Dynamic eccentricity: the rotor turns about an axis off its own centre, so its smallest air
    // gap turns with it and the magnet flux linked rises and falls once per mechanical turn,
    // psi_f (1 + eccentricity cos(theta_m + eccentricity_phase)).
    double eccentricity = 0.0;        // relative modulation of psi_f, [0, 0.5]
    double eccentricity_phase = 0.0;  // rad of the shaft angle, [-pi, pi]
};

// Saturation of the stator iron: the permeability falls with the armature's magnetic energy
// (docs/pmsm.md gives the law). 0 = linear iron.
struct SaturationDevice {
    double saturation_current = 0.0;  // A; the q flux tends to lq * saturation_current
};

struct CurrentSensorDevice {
    double offset_a = 0.0, offset_b = 0.0;  // A
    double gain_a = 1.0, gain_b = 1.0;      // measured / true
};

// Two-node thermal network: winding and magnet, each with a capacity, coupled to each other and to
// the ambient through thermal resistances; the copper loss (and an optional iron loss) heats the
// winding node. Off: both temperatures stay at their initial values.
struct ThermalNetwork {
    bool enabled = false;
    double winding_capacity = 40.0;     // J/K
    double magnet_capacity = 20.0;      // J/K
    double winding_to_magnet = 4.0;     // K/W
    double winding_to_ambient = 6.0;    // K/W
    double magnet_to_ambient = 15.0;    // K/W
    double ambient = 20.0;              // °C
    double initial_winding = 20.0;      // °C
    double initial_magnet = 20.0;       // °C
    double iron_loss = 0.0;             // W s^2/rad^2: loss k omega_e^2, heating the winding node
    double alpha_magnet = -0.0012;      // 1/K, psi_f(T) = psi_f20 (1 + alpha (T - 20)) (NdFeB)
};

inline constexpr double copper_temperature_coefficient = 0.00393;  // 1/K, R(T) = R20 (1 + a (T - 20))

// Offset of the logging channels of u_d and u_q (ADC offset): what is logged, not what is applied.
struct LoggingOffset {
    double u_d = 0.0, u_q = 0.0;  // V
};

struct DeviceSettings {
    InverterDevice inverter;
    EncoderDevice encoder;
    RotorFluxDevice rotor_flux;
    SaturationDevice saturation;
    CurrentSensorDevice current_sensors;
    ThermalNetwork thermal;
    LoggingOffset logging_offset;
};

struct DriveControl;

// Refuses device settings that cannot describe a drive with these control settings
// (std::invalid_argument naming the setting).
void check_device_settings(const DeviceSettings& device, const DriveControl& control);

}  // namespace mhb::pmsm

#include "problems/pmsm/simulation/device_plant.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/simulation/drive_configuration.hpp"
#include "problems/pmsm/simulation/thermal_network.hpp"

namespace mhb::pmsm {

namespace {

// Gate state of one inverter leg.
enum class Gate { lower, upper, none };

class DevicePlant final : public ControlledPlant {
public:
    explicit DevicePlant(const DriveSimulation& spec)
        : spec_(spec), device_(*spec.device), pole_pairs_(spec.motor.pole_pairs), inertia_(spec.mechanics.total_inertia()),
          carriers_per_control_(std::llround(spec.control.control_period * device_.inverter.pwm_frequency)),
          carrier_period_(spec.control.control_period / static_cast<double>(carriers_per_control_)),
          thermal_(device_.thermal, spec.control.control_period) {
        flux_ = plant_flux_model(spec);
        for (const auto& h : device_.rotor_flux.harmonics) {
            std::array<Complex, 3> turns;
            for (std::size_t x = 0; x < 3; ++x) turns[x] = std::polar(1.0, -2.0 * std::numbers::pi * h.order * static_cast<double>(x) / 3.0);
            phase_turns_.push_back(turns);
        }
        count_angle_ = device_.encoder.lines > 0 ? 2.0 * std::numbers::pi / (4.0 * static_cast<double>(device_.encoder.lines)) : 0.0;
        update_coefficients();
        // At rest the stator links the magnet flux only.
        const Magnet magnet = magnet_flux(0.0);
        x_.psi = inverse_park(flux_->flux({0.0, 0.0}, eccentric_magnet_flux(0.0)), 0.0) + magnet.harmonic_flux;
    }

    SensorReading sense(double, Rng& rng) override {
        const Electrical e = electrical(x_);
        const auto& s = device_.current_sensors;
        double i_a = s.gain_a * e.phase[0] + s.offset_a, i_b = s.gain_b * e.phase[1] + s.offset_b;
        if (spec_.noise.current > 0) {
            i_a += spec_.noise.current * rng.normal();
            i_b += spec_.noise.current * rng.normal();
        }
        SensorReading r;
        r.current = clarke(i_a, i_b, -i_a - i_b);
        const double shaft = count_angle_ > 0 ? std::floor(x_.theta_m / count_angle_) * count_angle_ : x_.theta_m;
        r.angle = wrap_angle(pole_pairs_ * shaft + device_.encoder.offset);
        r.shaft_angle = wrap_angle(shaft);
        r.true_speed = pole_pairs_ * x_.omega_m;
        return r;
    }

    // The duty cycles computed now are loaded at the next carrier peak that starts a control period:
    // this period runs on the previous ones.
    void run_control_period(double, Complex voltage_reference, const SensorReading& reading, double measured_speed,
                            const Segment& segment) override {
        double copper_energy = 0.0;
        for (std::int64_t k = 0; k < carriers_per_control_; ++k)
            copper_energy += run_carrier_period(segment.load_torque);
        const double ts = spec_.control.control_period;
        const double omega_e = pole_pairs_ * x_.omega_m;
        thermal_.advance(copper_energy / ts + device_.thermal.iron_loss * omega_e * omega_e);
        update_coefficients();

        // Modulation: inverse Park at the angle where the vector will be applied on average (1.5 T_s
        // after the sample) when compensating, phase references, min-max zero sequence, duties.
        const double advance = device_.inverter.delay_compensation ? 1.5 * measured_speed * ts : 0.0;
        const auto phase = inverse_clarke(inverse_park(voltage_reference, reading.angle + advance));
        const double zero_sequence = -0.5 * (std::max({phase[0], phase[1], phase[2]}) + std::min({phase[0], phase[1], phase[2]}));
        for (int x = 0; x < 3; ++x)
            duty_[x] = std::clamp(0.5 + (phase[x] + zero_sequence) / spec_.control.dc_voltage, 0.0, 1.0);
    }

    Temperatures temperatures(double) const override { return {thermal_.winding(), thermal_.magnet()}; }
    Complex logged_voltage_offset() const override { return {device_.logging_offset.u_d, device_.logging_offset.u_q}; }
    std::int64_t integration_steps() const override { return steps_; }

private:
    struct State {
        Complex psi;           // stator flux linkage, stationary alpha-beta frame (Wb)
        double omega_m = 0.0;  // shaft speed (rad/s)
        double theta_m = 0.0;  // shaft angle, wrapped to [-pi, pi) (rad)
    };
    struct Magnet {
        Complex harmonic_flux;                  // alpha-beta flux of the harmonics (Wb)
        std::array<double, 3> harmonic_slope{};  // d psi_harmonic,x / d theta_e per phase (Wb/rad)
    };
    struct Electrical {
        Complex current;                  // alpha-beta (A)
        std::array<double, 3> phase{};    // phase currents (A)
        double torque = 0.0;              // N m
    };

    void update_coefficients() {
        rs_ = spec_.motor.rs * (1.0 + copper_temperature_coefficient * (thermal_.winding() - reference_temperature));
        psi_f_ = spec_.motor.psi_f * (1.0 + device_.thermal.alpha_magnet * (thermal_.magnet() - reference_temperature));
    }

    // Magnet flux linked by phase x at theta_x = theta - 2 pi x / 3, beyond its fundamental:
    // psi_f sum_h k_h cos(h theta_x + phi_h), and its slope with the rotor angle. Each harmonic's
    // phasor e^{j(h theta + phi)} is turned by e^{-j 2 pi h x / 3} for phase x.
    Magnet magnet_flux(double theta) const {
        Magnet m;
        if (device_.rotor_flux.harmonics.empty()) return m;
        std::array<double, 3> flux{};
        for (std::size_t k = 0; k < device_.rotor_flux.harmonics.size(); ++k) {
            const auto& h = device_.rotor_flux.harmonics[k];
            const Complex phasor = std::polar(h.amplitude * psi_f_, h.order * theta + h.phase);
            for (std::size_t x = 0; x < 3; ++x) {
                const Complex e = phasor * phase_turns_[k][x];
                flux[x] += e.real();
                m.harmonic_slope[x] -= h.order * e.imag();
            }
        }
        m.harmonic_flux = clarke(flux[0], flux[1], flux[2]);
        return m;
    }

    // The magnet fundamental the stator links at shaft angle theta_m. An eccentric rotor turns its
    // smallest air gap with it, so the gap under the poles, and the flux they drive through the
    // winding, rises and falls once per turn: psi_f (1 + e cos(theta_m + phi)).
    double eccentric_magnet_flux(double theta_m) const {
        const auto& r = device_.rotor_flux;
        return r.eccentricity > 0.0 ? psi_f_ * (1.0 + r.eccentricity * std::cos(theta_m + r.eccentricity_phase)) : psi_f_;
    }

    // Currents and torque of a state: the harmonic flux is the magnet's, the rest is the machine's
    // dq flux (magnet fundamental and armature) in the rotor frame.
    Electrical electrical(const State& x) {
        const double theta = pole_pairs_ * x.theta_m;
        const Magnet magnet = magnet_flux(theta);
        const Complex rotor = std::polar(1.0, theta);
        const Complex psi_dq = (x.psi - magnet.harmonic_flux) * std::conj(rotor);
        guess_ = flux_->current(psi_dq, eccentric_magnet_flux(x.theta_m), guess_);
        Electrical e;
        e.current = guess_ * rotor;
        e.phase = inverse_clarke(e.current);
        // Torque: the dq machine's from its flux, the harmonics' from the power they convert,
        // p sum_x i_x d psi_x / d theta.
        e.torque = electromagnetic_torque(pole_pairs_, psi_dq, guess_);
        for (std::size_t k = 0; k < 3; ++k) e.torque += pole_pairs_ * e.phase[k] * magnet.harmonic_slope[k];
        // The co-energy 1.5 psi_f(theta_m) i_d changes with the shaft angle at fixed phase currents
        // when the rotor is eccentric: 1.5 i_d d psi_f / d theta_m more (exact for linear iron).
        if (const auto& r = device_.rotor_flux; r.eccentricity > 0.0)
            e.torque -= 1.5 * guess_.real() * psi_f_ * r.eccentricity * std::sin(x.theta_m + r.eccentricity_phase);
        return e;
    }

    // What the inverter holds at the terminals over an interval: source voltages (alpha-beta) and the
    // conducting devices' on-resistances, whose drop follows the current within the interval.
    struct Terminals {
        Complex source;
        std::array<double, 3> resistance{};
        bool resistive = false;
    };

    State rate(const State& x, const Electrical& e, const Terminals& u, double load_torque) const {
        State r;
        r.psi = u.source - rs_ * e.current;
        if (u.resistive)
            r.psi -= clarke(u.resistance[0] * e.phase[0], u.resistance[1] * e.phase[1], u.resistance[2] * e.phase[2]);
        r.omega_m = (e.torque - load_torque - spec_.mechanics.viscous_friction * x.omega_m) / inertia_;
        r.theta_m = x.omega_m;
        return r;
    }
    State rate(const State& x, const Terminals& u, double load_torque) { return rate(x, electrical(x), u, load_torque); }

    static State advanced(const State& x, const State& r, double h) {
        return {x.psi + h * r.psi, x.omega_m + h * r.omega_m, x.theta_m + h * r.theta_m};
    }

    // One RK4 step with the terminals u held, from the present state whose currents and torque are
    // `start`; returns the copper energy of the step (J).
    double step(double h, const Terminals& u, double load_torque, const Electrical& start) {
        const State k1 = rate(x_, start, u, load_torque);
        const State k2 = rate(advanced(x_, k1, 0.5 * h), u, load_torque);
        const State k3 = rate(advanced(x_, k2, 0.5 * h), u, load_torque);
        const State k4 = rate(advanced(x_, k3, h), u, load_torque);
        x_.psi += h / 6.0 * (k1.psi + 2.0 * k2.psi + 2.0 * k3.psi + k4.psi);
        x_.omega_m += h / 6.0 * (k1.omega_m + 2.0 * k2.omega_m + 2.0 * k3.omega_m + k4.omega_m);
        x_.theta_m = wrap_angle(x_.theta_m + h / 6.0 * (k1.theta_m + 2.0 * k2.theta_m + 2.0 * k3.theta_m + k4.theta_m));
        ++steps_;
        return rs_ * (start.phase[0] * start.phase[0] + start.phase[1] * start.phase[1] + start.phase[2] * start.phase[2]) * h;
    }

    // Leg x is on its upper transistor while the carrier (1 at the period's start and end, 0 in its
    // middle) is below its duty: [t_rise, t_fall], centred in the period. Every turn-on edge comes
    // dead_time late, so the upper gate conducts over [t_rise + t_d, t_fall) and the lower one outside
    // [t_rise, t_fall + t_d); in between neither does.
    Gate gate(int leg, double t) const {
        const double d = duty_[leg];
        if (d <= 0.0) return Gate::lower;
        if (d >= 1.0) return Gate::upper;
        const double t_rise = 0.5 * (1.0 - d) * carrier_period_, t_fall = 0.5 * (1.0 + d) * carrier_period_;
        const double t_d = device_.inverter.dead_time;
        if (t >= t_rise + t_d && t < t_fall) return Gate::upper;
        if (t < t_rise || t >= t_fall + t_d) return Gate::lower;
        return Gate::none;
    }

    struct LegConduction {
        double voltage = 0.0;     // V against the DC link's negative rail at zero current
        double resistance = 0.0;  // Ω of the conducting device: the leg voltage falls by resistance x i
    };

    // The gate decides which device may conduct, the current's direction which one does (a diode when
    // it flows against the transistor, both diodes' choice in the dead time).
    LegConduction leg(Gate g, double current) const {
        const auto& inv = device_.inverter;
        const double vdc = spec_.control.dc_voltage;
        const LegConduction upper_diode{vdc + inv.diode_drop, inv.diode_resistance},
            lower_diode{-inv.diode_drop, inv.diode_resistance};
        const bool outward = current > 0.0;  // out of the leg into the motor
        switch (g) {
        case Gate::upper: return outward ? LegConduction{vdc - inv.switch_drop, inv.switch_resistance} : upper_diode;
        case Gate::lower: return outward ? lower_diode : LegConduction{inv.switch_drop, inv.switch_resistance};
        case Gate::none: return outward ? lower_diode : upper_diode;
        }
        return {};
    }

    // One carrier period from a carrier peak: between switching instants the leg voltages are held
    // (which device conducts is decided by the current at the interval's start), and the machine is
    // integrated across each interval in equal RK4 sub-steps no longer than integration_step.
    double run_carrier_period(double load_torque) {
        std::array<double, 14> instants{};
        std::size_t n = 0;
        instants[n++] = 0.0;
        instants[n++] = carrier_period_;
        const double t_d = device_.inverter.dead_time;
        for (int leg = 0; leg < 3; ++leg) {
            const double d = duty_[leg];
            if (d <= 0.0 || d >= 1.0) continue;
            const double t_rise = 0.5 * (1.0 - d) * carrier_period_, t_fall = 0.5 * (1.0 + d) * carrier_period_;
            for (double t : {t_rise, t_rise + t_d, t_fall, t_fall + t_d}) instants[n++] = std::min(t, carrier_period_);
        }
        std::sort(instants.begin(), instants.begin() + static_cast<std::ptrdiff_t>(n));
        const double h_max = spec_.control.integration_step;
        double energy = 0.0;
        for (std::size_t k = 0; k + 1 < n; ++k) {
            const double begin = instants[k], length = instants[k + 1] - begin;
            if (length <= 1e-15 * carrier_period_) continue;
            const Electrical e = electrical(x_);
            const double middle = begin + 0.5 * length;
            std::array<LegConduction, 3> legs;
            for (std::size_t x = 0; x < 3; ++x) legs[x] = leg(gate(static_cast<int>(x), middle), e.phase[x]);
            Terminals u;
            u.source = clarke(legs[0].voltage, legs[1].voltage, legs[2].voltage);
            for (std::size_t x = 0; x < 3; ++x) u.resistance[x] = legs[x].resistance;
            u.resistive = u.resistance[0] > 0 || u.resistance[1] > 0 || u.resistance[2] > 0;
            const auto substeps = std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(length / h_max - 1e-9)));
            const double h = length / static_cast<double>(substeps);
            for (std::int64_t s = 0; s < substeps; ++s) energy += step(h, u, load_torque, s == 0 ? e : electrical(x_));
        }
        return energy;
    }

    const DriveSimulation& spec_;
    const DeviceSettings& device_;
    double pole_pairs_;
    double inertia_;
    std::int64_t carriers_per_control_;
    double carrier_period_;
    HeatedWindingAndMagnet thermal_;
    std::unique_ptr<FluxModel> flux_;
    std::vector<std::array<Complex, 3>> phase_turns_;  // per harmonic: e^{-j 2 pi h x / 3}, x = 0, 1, 2
    double count_angle_ = 0.0;  // shaft angle of one encoder count (rad); 0 = exact
    double rs_ = 0.0, psi_f_ = 0.0;
    std::array<double, 3> duty_{0.5, 0.5, 0.5};  // zero voltage before the first reference
    State x_;
    Complex guess_;
    std::int64_t steps_ = 0;
};

}  // namespace

std::unique_ptr<ControlledPlant> make_device_plant(const DriveSimulation& spec) {
    if (!spec.device) throw std::invalid_argument("make_device_plant: the simulation has no device settings");
    check_device_settings(*spec.device, spec.control);
    return std::make_unique<DevicePlant>(spec);
}

}  // namespace mhb::pmsm

#include "problems/pmsm/simulation/averaged_plant.hpp"

#include "problems/pmsm/machine/flux_models.hpp"

#include <cmath>
#include <numbers>

namespace mhb::pmsm {
namespace {

struct PlantState {
    Complex psi;           // total flux linkage, rotor frame (Wb)
    double omega_m = 0.0;  // motor shaft speed (rad/s)
    double theta_m = 0.0;  // motor shaft angle, wrapped to [-pi, pi) (rad)
};

struct PlantRate {
    Complex psi;
    double omega_m = 0.0;
    double theta_m = 0.0;
};

PlantState advance(const PlantState& x, const PlantRate& r, double h) {
    return {x.psi + h * r.psi, x.omega_m + h * r.omega_m, x.theta_m + h * r.theta_m};
}

// The plant: machine with its flux model and effects, and the rigid reflected mechanics.
class Plant {
public:
    Plant(const DriveSimulation& spec, std::unique_ptr<FluxModel> flux)
        : spec_(spec), flux_(std::move(flux)), pole_pairs_(spec.motor.pole_pairs),
          inertia_(spec.mechanics.total_inertia()) {}

    // Resistance and magnet flux at time t (temperature profiles through the thermal effects).
    void coefficients(double t, double& rs, double& psi_f) const {
        rs = spec_.motor.rs;
        psi_f = spec_.motor.psi_f;
        const PlantConditions c{spec_.temp_winding.at(t), spec_.temp_magnet.at(t)};
        for (const auto& e : spec_.effects) e->plant_coefficients(c, rs, psi_f);
    }

    double electrical_angle(const PlantState& x) const { return wrap_angle(pole_pairs_ * x.theta_m); }

    Complex ripple_flux(double theta_e, double psi_f) const {
        Complex r;
        for (const auto& e : spec_.effects) r += e->plant_flux_ripple(theta_e, psi_f);
        return r;
    }

    // Currents of state x (Newton from the last solution when the flux model is nonlinear).
    Complex current(const PlantState& x, double t) {
        double rs, psi_f;
        coefficients(t, rs, psi_f);
        const double theta = electrical_angle(x);
        guess_ = flux_->current(x.psi - ripple_flux(theta, psi_f), psi_f, guess_);
        return guess_;
    }

    // State derivative with `u` the voltage reaching the terminals before the inverter's losses.
    PlantRate rate(const PlantState& x, double t, Complex u, double load_torque) {
        double rs, psi_f;
        coefficients(t, rs, psi_f);
        const double theta = electrical_angle(x);
        const Complex ripple = ripple_flux(theta, psi_f);
        const Complex psi_machine = x.psi - ripple;
        guess_ = flux_->current(psi_machine, psi_f, guess_);
        const Complex i = guess_;
        Complex emf_ripple;
        for (const auto& e : spec_.effects) {
            u -= e->plant_inverter_loss(theta, i);
            emf_ripple += e->plant_emf_ripple(theta, psi_f);
        }
        const double omega_e = pole_pairs_ * x.omega_m;
        // Torque: the machine part from its flux, the magnet-harmonic part from its back-EMF.
        const double torque = electromagnetic_torque(pole_pairs_, psi_machine, i) +
                              1.5 * pole_pairs_ * (emf_ripple * std::conj(i)).real();
        PlantRate r;
        r.psi = u - rs * i - Complex{0.0, omega_e} * x.psi;
        r.omega_m = (torque - load_torque - spec_.mechanics.viscous_friction * x.omega_m) / inertia_;
        r.theta_m = x.omega_m;
        return r;
    }

    // One RK4 step of length h with the terminal voltage u held.
    void step(PlantState& x, double t, double h, Complex u, double load_torque) {
        const PlantRate k1 = rate(x, t, u, load_torque);
        const PlantRate k2 = rate(advance(x, k1, 0.5 * h), t + 0.5 * h, u, load_torque);
        const PlantRate k3 = rate(advance(x, k2, 0.5 * h), t + 0.5 * h, u, load_torque);
        const PlantRate k4 = rate(advance(x, k3, h), t + h, u, load_torque);
        x.psi += h / 6.0 * (k1.psi + 2.0 * k2.psi + 2.0 * k3.psi + k4.psi);
        x.omega_m += h / 6.0 * (k1.omega_m + 2.0 * k2.omega_m + 2.0 * k3.omega_m + k4.omega_m);
        x.theta_m = wrap_angle(x.theta_m + h / 6.0 * (k1.theta_m + 2.0 * k2.theta_m + 2.0 * k3.theta_m + k4.theta_m));
    }

    PlantState rest_state() {
        double rs, psi_f;
        coefficients(0.0, rs, psi_f);
        PlantState x;
        x.psi = flux_->flux({0.0, 0.0}, psi_f) + ripple_flux(0.0, psi_f);
        guess_ = {0.0, 0.0};
        return x;
    }

private:
    const DriveSimulation& spec_;
    std::unique_ptr<FluxModel> flux_;
    int pole_pairs_;
    double inertia_;
    Complex guess_;
};

// The averaged plant as the drive sees it: the effects' sensor hooks, their inverter command
// shortfall and delay line in front of the machine, and the prescribed temperature profiles.
class AveragedPlant final : public ControlledPlant {
public:
    explicit AveragedPlant(const DriveSimulation& spec)
        : spec_(spec), plant_(spec, plant_flux_model(spec)),
          steps_per_control_(whole_ratio(spec.control.control_period, spec.control.integration_step,
                                         "control_period / integration_step")),
          h_(spec.control.control_period / static_cast<double>(steps_per_control_)) {
        double delay = 0.0;
        for (const auto& e : spec.effects) {
            angle_offset_ += e->plant_angle_offset();
            sensor_offset_ += e->plant_current_sensor_offset();
            delay += e->plant_delay();
            shortfall_ += e->plant_command_shortfall();
        }
        // Delay line of the inverter: commands and true angles, one entry per integration step.
        delay_steps_ = static_cast<std::size_t>(std::llround(delay / h_));
        command_history_.resize(delay_steps_ + 1);
        angle_history_.resize(delay_steps_ + 1);
        x_ = plant_.rest_state();
    }

    SensorReading sense(double t, Rng& rng) override {
        // Two phase currents and the encoder angle, as the controller sees them.
        const double theta_true = plant_.electrical_angle(x_);
        const auto phase = inverse_clarke(inverse_park(plant_.current(x_, t), theta_true));
        double i_a = phase[0], i_b = phase[1];
        if (spec_.noise.current > 0) {
            i_a += spec_.noise.current * rng.normal();
            i_b += spec_.noise.current * rng.normal();
        }
        SensorReading r;
        r.current = Complex{i_a, (i_a + 2.0 * i_b) / std::numbers::sqrt3} + sensor_offset_;
        r.angle = wrap_angle(theta_true + angle_offset_);
        r.shaft_angle = x_.theta_m;
        r.true_speed = static_cast<double>(spec_.motor.pole_pairs) * x_.omega_m;
        return r;
    }

    // The command (less any shortfall) goes through the delay line and is applied in the controller's
    // rotating frame, which leads the rotor frame by the offset.
    void run_control_period(double t, Complex voltage_reference, const SensorReading&, double,
                            const Segment& segment) override {
        const Complex command = voltage_reference - shortfall_;
        for (std::int64_t n = 0; n < steps_per_control_; ++n, ++step_index_) {
            const double t_step = t + static_cast<double>(n) * h_;
            const double theta_now = plant_.electrical_angle(x_);
            const auto slot = static_cast<std::size_t>(step_index_) % command_history_.size();
            command_history_[slot] = command;
            angle_history_[slot] = theta_now;
            Complex applied;
            if (step_index_ >= static_cast<std::int64_t>(delay_steps_)) {
                const auto old = static_cast<std::size_t>(step_index_ - static_cast<std::int64_t>(delay_steps_)) % command_history_.size();
                const double lag = wrap_angle(theta_now - angle_history_[old]);
                applied = std::polar(1.0, angle_offset_ - lag) * command_history_[old];
            }
            plant_.step(x_, t_step, h_, applied, segment.load_torque);
        }
    }

    Temperatures temperatures(double t) const override { return {spec_.temp_winding.at(t), spec_.temp_magnet.at(t)}; }
    std::int64_t integration_steps() const override { return step_index_; }

private:
    const DriveSimulation& spec_;
    Plant plant_;
    std::int64_t steps_per_control_;
    double h_;
    double angle_offset_ = 0.0;
    Complex sensor_offset_, shortfall_;
    std::size_t delay_steps_ = 0;
    std::vector<Complex> command_history_;
    std::vector<double> angle_history_;
    std::int64_t step_index_ = 0;
    PlantState x_;
};

}  // namespace

std::unique_ptr<ControlledPlant> make_averaged_plant(const DriveSimulation& spec) { return std::make_unique<AveragedPlant>(spec); }

}  // namespace mhb::pmsm

#pragma once
// A physical effect missing from the base PMSM model (seed eq. 2), defined once for both sides:
//   - the plant side: where it acts in the simulated drive (inverter output, sensors, machine
//     coefficients, flux linkage), used by the drive simulator;
//   - the model side: its steady-state contribution to the logged reference voltages u_d, u_q, used
//     when fitting (it may be nonlinear in its parameters and may rescale base parameters).
// Each effect is one .cpp under problems/pmsm/effects/ that registers itself:
//
//   namespace { const bool registered = mhb::pmsm::register_effect({
//       "deadtime", "Inverter dead time and device drop", {ParameterSpec::real("voltage", ...)},
//       [](const ParameterSet& p) { return std::make_unique<DeadTime>(p); }}); }
//
// Real parameters (in declaration order) are what a fit varies; their declared range is the
// physically plausible range and doubles as the search box. Text parameters configure the plant only.
#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "framework/parameters.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/machine/machine.hpp"

namespace mhb::pmsm {

// The steady-state model evaluated over all samples at once. It starts from the logged data and
// walks the physical chain outward to the logged voltage; each stage is a place where effects act.
//   SensorCurrents  measured currents -> currents the sensors really saw (controller frame)
//   SensorAngle     controller frame -> true rotor frame (currents and angle)
//   Coefficients    per-sample resistance and magnet flux (temperatures)
//   FluxLinkage     flux linkages from currents (after psi_d = Ld i_d + psi_f, psi_q = Lq i_q)
//   MachineVoltage  extra machine voltage (after u = rs i + j omega psi)
//   CurrentRipple   L di/dt of a ripple that sensor errors make the true currents carry while the
//                   logged ones hold still: the steady state's only di/dt (a dynamic model has its own
//                   and leaves this stage out)
//   InverterError   what the inverter loses between command and terminals (true frame)
//   ControllerFrame true rotor frame -> controller frame (voltage)
//   Delay           applied voltage -> the earlier command that produced it
//   LoggedVoltage   command -> logged reference
// A bias on the base parameters that no steady-state log shows (Effect::unseen_bias): one sentence
// for the user, and which of Rs, Ld, Lq and psi_f it moves (their intervals do not hold it).
struct UnseenBias {
    std::string text;
    std::array<bool, 4> base{true, true, true, true};
};

enum class ModelStage : unsigned {
    SensorCurrents = 1u << 0,
    SensorAngle = 1u << 1,
    Coefficients = 1u << 2,
    FluxLinkage = 1u << 3,
    MachineVoltage = 1u << 4,
    InverterError = 1u << 5,
    ControllerFrame = 1u << 6,
    Delay = 1u << 7,
    LoggedVoltage = 1u << 8,
    CurrentRipple = 1u << 9,  // runs right after MachineVoltage
};
constexpr unsigned operator|(ModelStage a, ModelStage b) { return static_cast<unsigned>(a) | static_cast<unsigned>(b); }
constexpr unsigned operator|(unsigned a, ModelStage b) { return a | static_cast<unsigned>(b); }
constexpr bool acts_in(unsigned stages, ModelStage s) { return (stages & static_cast<unsigned>(s)) != 0; }

// How an effect's model side depends on the base parameters (Rs, Ld, Lq, psi_f) at a stage from
// Coefficients on, where they have entered the state. A fit splits every prediction into a part
// without the base parameters and one per base parameter (the prediction is affine in them,
// model_fit.hpp); an effect that says how it depends lets that split skip work.
enum class BaseDependence {
    Affine,    // not stated: any affine map of the state (always correct; costs one more model run)
    Linear,    // a linear map of what the base parameters made: scales, rotates, adds terms proportional to it
    Additive,  // adds a term of its own that no base parameter changes (a voltage, a flux)
};

// Per-sample quantities of the steady-state model over a block of consecutive rows (the model is
// evaluated a block at a time so that these stay in cache); every array has the block's length.
struct ModelState {
    Eigen::ArrayXd i_d, i_q;            // A: measured (controller frame), then true (rotor frame)
    Eigen::ArrayXd theta;               // rad: logged angle, then true angle (empty without theta_e)
    // cos and sin of theta, kept in step with it (rotate_angle), so effects need no sincos per sample.
    Eigen::ArrayXd cos_theta, sin_theta;
    Eigen::ArrayXd omega;               // rad/s electrical
    Eigen::ArrayXd rs, psi_f;           // Ω, Wb per sample
    double ld = 0.0, lq = 0.0;          // H: the inductances psi_d and psi_q were made with (the base lane's unit ones in a fit's split)
    Eigen::ArrayXd psi_d, psi_q;        // Wb
    Eigen::ArrayXd u_d, u_q;            // V: machine terminal voltage, then command, then logged
    // Logged temperatures (°C), empty when the data have none.
    Eigen::ArrayXd temp_winding, temp_magnet;

    Eigen::Index size() const { return i_d.size(); }
    // Sizes the arrays every model has; the angle and temperature arrays are sized by whoever loads
    // the rows (SteadyStateModel), as the data have them.
    void resize(Eigen::Index n);
    // theta += delta, with its cos and sin.
    void rotate_angle(double delta);
};

// The size of the currents and flux linkages a model or a plant works at, for effects whose
// parameters are stated per unit of them or whose plausible range follows them. A model takes it
// from the logged data (model/steady_state_model.hpp: the largest logged current, the largest
// |u| / |omega| where the speed is not small), a plant from its drive (the current limit, the magnet
// flux); 1 A and 1 Wb until one of them sets it.
struct OperatingScale {
    double current = 1.0;  // A: largest current amplitude
    double flux = 1.0;     // Wb: largest flux-linkage amplitude
};

// What the plant knows at an instant, for effects that depend on operating conditions.
struct PlantConditions {
    double temp_winding = reference_temperature;  // °C
    double temp_magnet = reference_temperature;   // °C
};

class Effect {
public:
    Effect(std::string name, const ParameterSet& settings);
    virtual ~Effect() = default;

    const std::string& name() const { return name_; }
    // Real parameters in declaration order: the plant uses these values, a fit varies them.
    const std::vector<std::string>& parameter_names() const { return parameter_names_; }
    const Eigen::VectorXd& values() const { return values_; }
    const std::vector<ParameterSpec>& parameter_specs() const { return specs_; }
    const ParameterSet& settings() const { return settings_; }
    const OperatingScale& scale() const { return scale_; }
    void set_scale(const OperatingScale& scale) { scale_ = scale; }

    // ---- plant side: defaults do nothing ----
    // Measured electrical angle minus the true one (rad).
    virtual double plant_angle_offset() const { return 0.0; }
    // Alpha-beta current added by the current sensors to what they measure (A).
    virtual Complex plant_current_sensor_offset() const { return {}; }
    // Time from the controller's reference to the inverter output (s).
    virtual double plant_delay() const { return 0.0; }
    // Controller-frame voltage by which the inverter's input falls short of the logged reference (V).
    virtual Complex plant_command_shortfall() const { return {}; }
    // Resistance and magnet flux under the present conditions (called with nominal values first).
    virtual void plant_coefficients(const PlantConditions&, double& /*rs*/, double& /*psi_f*/) const {}
    // A flux model replacing the linear one (nullptr: keep it), at the plant's scale (its current
    // limit and magnet flux). Paths resolve against base_directory.
    virtual std::unique_ptr<FluxModel> plant_flux_model(const MotorParameters&, const OperatingScale& /*plant*/,
                                                        const std::filesystem::path& /*base_directory*/) const {
        return nullptr;
    }
    // Angle-dependent part of the magnet flux (rotor frame, Wb) and its back-EMF per unit speed,
    // (d/dtheta + j) of it (V s/rad), which the plant also needs for the torque.
    virtual Complex plant_flux_ripple(double /*theta_e*/, double /*psi_f*/) const { return {}; }
    virtual Complex plant_emf_ripple(double /*theta_e*/, double /*psi_f*/) const { return {}; }
    // Voltage the inverter loses at its terminals, rotor frame, given the true angle and currents (V).
    virtual Complex plant_inverter_loss(double /*theta_e*/, Complex /*i_dq*/) const { return {}; }

    // ---- model side ----
    // Stages this effect acts in (ModelStage bits) and the optional data columns it needs.
    virtual unsigned model_stages() const { return 0; }
    virtual std::vector<std::string> model_columns() const { return {}; }
    // Applies the effect at `stage` with parameters p (this effect's real parameters, in order).
    virtual void model(ModelStage /*stage*/, const double* /*p*/, ModelState& /*state*/) const {}
    // How model() at `stage` depends on the base parameters (see BaseDependence); stages before
    // Coefficients are never asked.
    virtual BaseDependence model_base_dependence(ModelStage /*stage*/) const { return BaseDependence::Affine; }
    // Whether model() at `stage`, from Coefficients on, may change what the sensor stages left: the
    // currents, the speed, the angle with its cos and sin, the temperatures. A fit's affine split runs
    // the later stages once per base parameter from the same inputs, and copies them back before each
    // run only when some effect says it may (tests/pmsm_steady_state_model_test.cpp checks every
    // registered effect's answer). The default, true, is always correct.
    virtual bool model_changes_inputs(ModelStage /*stage*/) const { return true; }
    // Whether the prediction is linear in real parameter k (the others fixed), with any other library
    // effects beside this one: what model() adds at its stage is linear in it, and no later stage of
    // any effect is nonlinear in what earlier stages made (later stages use currents and the angle
    // nonlinearly, never voltages, fluxes or coefficients). Then one prediction gives its Jacobian
    // column exactly. Checked for every registered effect against every other one
    // (tests/pmsm_steady_state_model_test.cpp); an effect acting in the sensor stages never is.
    virtual bool model_linear_in(std::size_t /*k*/) const { return false; }
    // Whether real parameter k is a size of the effect (at zero the effect vanishes), not a shape:
    // a diagnosis states the smallest size each effect could have and still show in a log
    // (diagnosis/detection_limits.hpp). The linear parameters unless the effect says otherwise.
    virtual bool is_size(std::size_t k) const { return model_linear_in(k); }
    // How closely the effect's law follows real machines: the rms error it is known to leave, as a
    // fraction of the flux linkage (0: exact, as an offset or a delay is). Residual structure within
    // it is the law's own error, not a missing effect (docs/diagnosis.md, "The laws' accuracy").
    virtual double law_accuracy() const { return 0.0; }
    // A bias the effect puts on the base parameters that no steady-state log can show, so that no
    // interval holds it, told to the user (text empty: none). `base` holds Rs, Ld, Lq and psi_f as fitted.
    virtual UnseenBias unseen_bias(const double* /*base*/) const { return {}; }

    // ---- what the data allow ----
    // Sets the plausible range [lo, hi] of real parameter k, given as the declared one, to what data
    // of this scale() can tell apart from other effects (e.g. a dead-time band wider than a fraction
    // of the logged current acts as a resistance). It may reach beyond the declared range on a
    // machine larger than the declaration foresaw; the fit's search box then stretches to twice
    // that width, so that a fit can still land beyond the plausible end and be reported.
    virtual void plausible_range(std::size_t /*k*/, double& /*lo*/, double& /*hi*/) const {}
    // What it means when real parameter k sits at the lower (or upper) end of its range, for the
    // user; empty when nothing more than "at the end of its range" can be said.
    virtual std::string range_end_meaning(std::size_t /*k*/, bool /*upper*/) const { return {}; }
    // Whether real parameter k at an end of its range makes the fit implausible: true for a physical
    // magnitude; false for a shape (a knee, an exponent), whose range is only as far as the law goes.
    virtual bool range_end_implausible(std::size_t /*k*/) const { return true; }
    // The value real parameter k has in the machine's material, when its range is one material's
    // spread (copper's temperature coefficient), not a span of materials; none otherwise. A fit that
    // leaves it at an end of its plausible range is refitted with it held at this value, and kept so
    // when the data cannot tell the two apart (docs/diagnosis.md, section 2).
    virtual std::optional<double> material_value(std::size_t /*k*/) const { return std::nullopt; }
    // The law's separate terms, each the real parameters only it uses, its size first: held at their
    // declared defaults (a size's default is zero) they drop that term. A law of several terms that
    // the log's operating points cannot pin as a whole is offered to the search with fewer of them
    // (docs/diagnosis.md, section 1). Empty: the law is one term.
    virtual std::vector<std::vector<std::size_t>> law_terms() const { return {}; }
    // The harmonics of the electrical angle (orders 1, 2, ... in the rotor frame) that the law puts
    // in the modelled voltage, and so where its own error on a rippling current lies: dead time's
    // six-step loss 6, 12, ...; an offset of a phase current's sensor 1. Empty: none (the law does
    // not depend on the angle). A harmonic left in a residual at an order that no law of the library
    // makes is physics outside it (docs/diagnosis.md, section 3). The default, every order, claims
    // them all: a law that does not say cannot be told from one that makes any harmonic.
    virtual std::vector<int> angle_orders() const { return every_angle_order(); }
    static std::vector<int> every_angle_order();
    // Why the whole model is physically impossible with these effect parameters p and base parameters
    // base (Rs, Ld, Lq, psi_f) at the rotor-frame currents (i_d, i_q) of the log; empty when possible.
    virtual std::string implausible_reason(const double* /*p*/, const double* /*base*/, const Eigen::ArrayXd& /*i_d*/,
                                           const Eigen::ArrayXd& /*i_q*/) const {
        return {};
    }

private:
    std::string name_;
    ParameterSet settings_;
    std::vector<ParameterSpec> specs_;
    std::vector<std::string> parameter_names_;
    Eigen::VectorXd values_;
    OperatingScale scale_;
};

using EffectFactory = std::function<std::unique_ptr<Effect>(const ParameterSet&)>;
using EffectRegistry = Registry<EffectFactory>;

inline bool register_effect(PluginEntry<EffectFactory> entry) { return EffectRegistry::instance().add(std::move(entry)); }

// Creates a registered effect with user values (ParameterError on bad values, UnknownPlugin on a
// name that is not registered).
std::unique_ptr<Effect> make_effect(const std::string& name, const std::map<std::string, ParameterValue>& values = {});

}  // namespace mhb::pmsm

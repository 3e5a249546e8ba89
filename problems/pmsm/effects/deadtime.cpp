// Inverter dead time and device voltage drop. Each phase loses V_dt in the direction of its current,
// V_dt = t_dead f_sw V_dc + V_device; near zero current the loss is taken as linear over a band
// (the current ripple and snubber charge make it so). In dq this is (4/pi) V_dt i/|i| plus a 6 omega
// ripple: an "extra resistance" that is largest at small current.
#include <algorithm>
#include <limits>
#include <numbers>

#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {
namespace {

double phase_sign(double i, double band) {
    if (band > 0.0) return std::clamp(i / band, -1.0, 1.0);
    return i > 0.0 ? 1.0 : (i < 0.0 ? -1.0 : 0.0);
}

// Voltage lost at the terminals, rotor frame, from the three phase currents; `rotor` is e^{j theta}.
Complex terminal_loss(double voltage, double band, Complex rotor, Complex i_dq) {
    const auto phase = inverse_clarke(i_dq * rotor);
    return clarke(voltage * phase_sign(phase[0], band), voltage * phase_sign(phase[1], band), voltage * phase_sign(phase[2], band)) *
           std::conj(rotor);
}

class DeadTime final : public Effect {
public:
    explicit DeadTime(const ParameterSet& p) : Effect("deadtime", p) {}

    Complex plant_inverter_loss(double theta, Complex i) const override {
        return terminal_loss(values()[0], values()[1], std::polar(1.0, theta), i);
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::InverterError); }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Additive; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        if (s.theta.size() > 0) {
            // terminal_loss written out in real arithmetic, without a branch, so that the compiler
            // vectorises it: this loop is a sixth of a long-log diagnosis.
            const double voltage = p[0], band = p[1];
            const double to_sign = band > 0.0 ? 1.0 / band : std::numeric_limits<double>::infinity();
            const double half_root3 = 0.5 * std::numbers::sqrt3;
            auto sign_of = [&](double i) { return band > 0.0 ? std::clamp(i * to_sign, -1.0, 1.0) : (i > 0.0) - (i < 0.0) + 0.0; };
            for (Eigen::Index k = 0; k < s.u_d.size(); ++k) {
                const double c = s.cos_theta[k], sn = s.sin_theta[k];
                const double alpha = s.i_d[k] * c - s.i_q[k] * sn, beta = s.i_d[k] * sn + s.i_q[k] * c;
                const double a = sign_of(alpha), b = sign_of(-0.5 * alpha + half_root3 * beta), cc = sign_of(-0.5 * alpha - half_root3 * beta);
                const double v_alpha = voltage * (2.0 * a - b - cc) / 3.0, v_beta = voltage * (b - cc) / std::numbers::sqrt3;
                s.u_d[k] += v_alpha * c + v_beta * sn;
                s.u_q[k] += v_beta * c - v_alpha * sn;
            }
            return;
        }
        // Without the angle only the fundamental is known: (4/pi) V_dt along the current.
        const double gain = 4.0 / std::numbers::pi * p[0];
        for (Eigen::Index k = 0; k < s.u_d.size(); ++k) {
            const double magnitude = std::hypot(s.i_d[k], s.i_q[k]);
            if (magnitude == 0.0) continue;
            s.u_d[k] += gain * s.i_d[k] / magnitude;
            s.u_q[k] += gain * s.i_q[k] / magnitude;
        }
    }
};

const bool registered = register_effect({
    "deadtime",
    "Inverter dead time and device drop: each phase loses V_dt against its current",
    {ParameterSpec::real("voltage", 0.28, 0.0, 10.0, "per-phase voltage error t_dead f_sw V_dc + V_device", "V"),
     ParameterSpec::real("current_band", 0.0, 0.0, 10.0,
                         "phase current over which the error ramps linearly through zero (0: a sign)", "A")},
    [](const ParameterSet& p) { return std::make_unique<DeadTime>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

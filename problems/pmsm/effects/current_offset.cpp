// Current-sensor offsets on phases a and b (phase c is computed as -a - b, as in most drives). The
// measured alpha-beta current carries the constant (o_a, (o_a + 2 o_b)/sqrt 3); in the rotating frame
// that is a ripple o at the electrical frequency, which the current loop imposes on the true currents
// i_m - o. The ripple turns at the electrical speed, so it has an L di/dt the steady state lacks:
// -L d o/dt = omega L J o, which cancels the ripple's share of j omega L (i_m - o) on an isotropic
// machine (u = R (i_m - o) + j omega L i_m + j omega psi_f) and leaves omega (L J - J L) o of the
// saliency. Without it the term claims (R + j omega L) o where the data hold R o: a thousand times
// too much on a machine whose omega L / R is large.
#include <algorithm>

#include <fmt/format.h>

#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {
namespace {

inline constexpr double max_offset_fraction = 0.02;

Complex alpha_beta_offset(double offset_a, double offset_b) {
    return {offset_a, (offset_a + 2.0 * offset_b) / std::numbers::sqrt3};
}

class CurrentOffset final : public Effect {
public:
    explicit CurrentOffset(const ParameterSet& p) : Effect("current_offset", p) {}

    Complex plant_current_sensor_offset() const override { return alpha_beta_offset(values()[0], values()[1]); }

    unsigned model_stages() const override { return ModelStage::SensorCurrents | ModelStage::CurrentRipple; }
    bool model_changes_inputs(ModelStage) const override { return false; }
    // omega L J o: proportional to L_d and L_q.
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    bool is_size(std::size_t) const override { return true; }
    std::vector<int> angle_orders() const override { return {1}; }  // a stator-frame offset turns once per period in the rotor frame
    // A sensor's offset is a fraction of its full scale, and a drive's sensors are sized to its
    // currents: up to 1 % of a full scale about twice the largest current logged (Hall sensors before
    // calibration; the 5 kW and 100 kW profiles log up to 0.54 and 0.6 of theirs). The declared
    // 0.5 A is a servo's or a small drive's; on a larger machine the log's fraction extends it.
    void plausible_range(std::size_t, double& lo, double& hi) const override {
        hi = std::max(hi, max_offset_fraction * scale().current);
        lo = std::min(lo, -max_offset_fraction * scale().current);
    }
    std::string range_end_meaning(std::size_t, bool) const override {
        return fmt::format("an offset this large (beyond {:g} of the largest logged current and the declared 0.5 A) is a faulty sensor, or "
                           "takes the place of another effect",
                           max_offset_fraction);
    }
    std::vector<std::string> model_columns() const override { return {"theta_e"}; }
    void model(ModelStage stage, const double* p, ModelState& s) const override {
        // In the sensor stage the angle is the logged one, the controller's, the frame the offset was
        // measured in; in the ripple's stage it is the true one, the frame of the voltage equation.
        const Complex o = alpha_beta_offset(p[0], p[1]);
        if (stage == ModelStage::SensorCurrents) {
            s.i_d -= o.real() * s.cos_theta + o.imag() * s.sin_theta;
            s.i_q -= -o.real() * s.sin_theta + o.imag() * s.cos_theta;
            return;
        }
        // omega L J o = omega (-L_d o_q, L_q o_d).
        s.u_d -= s.omega * s.ld * (-o.real() * s.sin_theta + o.imag() * s.cos_theta);
        s.u_q += s.omega * s.lq * (o.real() * s.cos_theta + o.imag() * s.sin_theta);
    }
};

const bool registered = register_effect({
    "current_offset",
    "Offsets of the phase a and b current sensors (needs theta_e)",
    {ParameterSpec::real("offset_a", 0.001, -0.5, 0.5, "offset of the phase a current sensor", "A"),
     ParameterSpec::real("offset_b", 0.0, -0.5, 0.5, "offset of the phase b current sensor", "A")},
    [](const ParameterSet& p) { return std::make_unique<CurrentOffset>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

// Slot harmonics of the magnet flux: the 11th and 13th spatial harmonics that stator slotting puts
// on the back-EMF. Phase a carries psi_f [cos theta + h11 cos(11 theta + phi11) + h13 cos(13 theta + phi13)];
// the 11th is a negative and the 13th a positive sequence, so in the rotor frame both turn at 12 theta:
//   psi_r = psi_f [h11 e^{-j(12 theta + phi11)} + h13 e^{j(12 theta + phi13)}]
//   EMF   = j omega psi_f [-11 h11 e^{-j(12 theta + phi11)} + 13 h13 e^{j(12 theta + phi13)}]
#include "problems/pmsm/effects/effect.hpp"

namespace {

using mhb::pmsm::Complex;

// One formula for both sides: p = {h11, phi11, h13, phi13}.
Complex ripple_flux(const double* p, double theta, double psi_f) {
    return psi_f * (p[0] * std::polar(1.0, -(12.0 * theta + p[1])) + p[2] * std::polar(1.0, 12.0 * theta + p[3]));
}
Complex ripple_emf(const double* p, double theta, double psi_f) {
    return Complex{0.0, psi_f} *
           (-11.0 * p[0] * std::polar(1.0, -(12.0 * theta + p[1])) + 13.0 * p[2] * std::polar(1.0, 12.0 * theta + p[3]));
}

class SlotHarmonic final : public mhb::pmsm::Effect {
public:
    explicit SlotHarmonic(const mhb::ParameterSet& p) : Effect("slot_harmonic", p) {}

    // Plant side: where the simulated machine carries it.
    Complex plant_flux_ripple(double theta, double psi_f) const override { return ripple_flux(values().data(), theta, psi_f); }
    Complex plant_emf_ripple(double theta, double psi_f) const override { return ripple_emf(values().data(), theta, psi_f); }

    // Model side: the term it adds to the predicted voltages, on all samples at once.
    unsigned model_stages() const override { return static_cast<unsigned>(mhb::pmsm::ModelStage::MachineVoltage); }
    std::vector<std::string> model_columns() const override { return {"theta_e"}; }
    // Both harmonics turn at 12 theta in the rotor frame: a diagnosis can then tell a 12th harmonic
    // this law takes from one it cannot make.
    std::vector<int> angle_orders() const override { return {12}; }
    void model(mhb::pmsm::ModelStage, const double* p, mhb::pmsm::ModelState& s) const override {
        for (Eigen::Index k = 0; k < s.u_d.size(); ++k) {
            const Complex e = s.omega[k] * ripple_emf(p, s.theta[k], s.psi_f[k]);
            s.u_d[k] += e.real();
            s.u_q[k] += e.imag();
        }
    }
};

const bool registered = mhb::pmsm::register_effect({
    "slot_harmonic",
    "11th and 13th (slot) harmonics of the magnet flux: a 12th-harmonic back-EMF in dq (needs theta_e)",
    {mhb::ParameterSpec::real("h11", 0.005, 0.0, 0.05, "11th-harmonic flux relative to psi_f", "1"),
     mhb::ParameterSpec::real("phi11", 0.0, -std::numbers::pi, std::numbers::pi, "phase of the 11th harmonic", "rad"),
     mhb::ParameterSpec::real("h13", 0.003, 0.0, 0.05, "13th-harmonic flux relative to psi_f", "1"),
     mhb::ParameterSpec::real("phi13", 0.0, -std::numbers::pi, std::numbers::pi, "phase of the 13th harmonic", "rad")},
    [](const mhb::ParameterSet& p) { return std::make_unique<SlotHarmonic>(p); },
});

}  // namespace

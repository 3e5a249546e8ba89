// Spatial harmonics of the magnet flux. Phase a carries psi_f [cos theta + h5 cos(5 theta + phi5)
// + h7 cos(7 theta + phi7)] (b, c shifted by 2 pi/3); the 5th is a negative and the 7th a positive
// sequence, so in the rotor frame both become a 6th harmonic:
//   psi_r = psi_f [h5 e^{-j(6 theta + phi5)} + h7 e^{j(6 theta + phi7)}],
//   back-EMF  d psi_r/dt + j omega psi_r = j omega psi_f [-5 h5 e^{-j(6 theta + phi5)} + 7 h7 e^{j(6 theta + phi7)}].
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {
namespace {

Complex ripple_flux(const double* p, double theta, double psi_f) {
    return psi_f * (p[0] * std::polar(1.0, -(6.0 * theta + p[1])) + p[2] * std::polar(1.0, 6.0 * theta + p[3]));
}

// The back-EMF of the ripple per unit electrical speed and flux is j [-5 h5 e^{-j(6 theta + phi5)}
// + 7 h7 e^{j(6 theta + phi7)}]: two fixed phasors, here once per parameter set, turned by e^{j 6 theta}.
struct EmfPhasors {
    Complex fifth, seventh;
    explicit EmfPhasors(const double* p)
        : fifth(Complex{0.0, -5.0 * p[0]} * std::polar(1.0, -p[1])), seventh(Complex{0.0, 7.0 * p[2]} * std::polar(1.0, p[3])) {}
    // Back-EMF per unit electrical speed (V s/rad); `sixth` is e^{j 6 theta}.
    Complex at(Complex sixth, double psi_f) const { return psi_f * (fifth * std::conj(sixth) + seventh * sixth); }
};

class FluxHarmonic final : public Effect {
public:
    explicit FluxHarmonic(const ParameterSet& p) : Effect("flux_harmonic", p) {}

    Complex plant_flux_ripple(double theta, double psi_f) const override { return ripple_flux(values().data(), theta, psi_f); }
    Complex plant_emf_ripple(double theta, double psi_f) const override {
        return EmfPhasors(values().data()).at(std::polar(1.0, 6.0 * theta), psi_f);
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::MachineVoltage); }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    std::vector<std::string> model_columns() const override { return {"theta_e"}; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        // EmfPhasors::at written out in real arithmetic (complex products keep a NaN branch that
        // stops vectorisation): fifth conj(sixth) + seventh sixth = (a c6 + b s6) + j (c c6 + d s6).
        const EmfPhasors emf(p);
        const double a = emf.fifth.real() + emf.seventh.real(), b = emf.fifth.imag() - emf.seventh.imag();
        const double c = emf.fifth.imag() + emf.seventh.imag(), d = emf.seventh.real() - emf.fifth.real();
        for (Eigen::Index k = 0; k < s.u_d.size(); ++k) {
            const double c1 = s.cos_theta[k], s1 = s.sin_theta[k];
            const double c2 = c1 * c1 - s1 * s1, s2 = 2.0 * c1 * s1;
            const double c4 = c2 * c2 - s2 * s2, s4 = 2.0 * c2 * s2;
            const double c6 = c4 * c2 - s4 * s2, s6 = s4 * c2 + c4 * s2;
            const double scale = s.omega[k] * s.psi_f[k];
            s.u_d[k] += scale * (a * c6 + b * s6);
            s.u_q[k] += scale * (c * c6 + d * s6);
        }
    }
};

const bool registered = register_effect({
    "flux_harmonic",
    "5th and 7th spatial harmonics of the magnet flux: a 6th-harmonic back-EMF in dq (needs theta_e)",
    {ParameterSpec::real("h5", 0.01, 0.0, 0.1, "5th-harmonic flux relative to psi_f", "1"),
     ParameterSpec::real("phi5", 0.0, -std::numbers::pi, std::numbers::pi, "phase of the 5th harmonic", "rad"),
     ParameterSpec::real("h7", 0.005, 0.0, 0.1, "7th-harmonic flux relative to psi_f", "1"),
     ParameterSpec::real("phi7", 0.0, -std::numbers::pi, std::numbers::pi, "phase of the 7th harmonic", "rad")},
    [](const ParameterSet& p) { return std::make_unique<FluxHarmonic>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

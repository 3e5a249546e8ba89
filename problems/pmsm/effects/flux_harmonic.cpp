// Spatial harmonics of the magnet flux. Phase a carries psi_f [cos theta + h5 cos(5 theta + phi5)
// + h7 cos(7 theta + phi7)] (b, c shifted by 2 pi/3); the 5th is a negative and the 7th a positive
// sequence, so in the rotor frame both become a 6th harmonic:
//   psi_r = psi_f [h5 e^{-j(6 theta + phi5)} + h7 e^{j(6 theta + phi7)}],
//   back-EMF  d psi_r/dt + j omega psi_r = j omega psi_f [-5 h5 e^{-j(6 theta + phi5)} + 7 h7 e^{j(6 theta + phi7)}].
#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {
namespace {

Complex ripple_flux(const double* p, double theta, double psi_f) {
    return psi_f * (p[0] * std::polar(1.0, -(6.0 * theta + p[1])) + p[2] * std::polar(1.0, 6.0 * theta + p[3]));
}

// The back-EMF of the ripple per unit electrical speed and flux is j [-5 h5 e^{-j(6 theta + phi5)}
// + 7 h7 e^{j(6 theta + phi7)}]: two fixed phasors F and S, here once per parameter set, turned by
// e^{j 6 theta} = c6 + j s6. F conj(e^{j 6 theta}) + S e^{j 6 theta} = (a c6 + b s6) + j (c c6 + d s6),
// kept as those four reals because complex products keep a NaN branch that stops the model's loop
// over a block of rows from vectorising.
class EmfPhasors {
public:
    explicit EmfPhasors(const double* p) {
        const Complex fifth = Complex{0.0, -5.0 * p[0]} * std::polar(1.0, -p[1]);
        const Complex seventh = Complex{0.0, 7.0 * p[2]} * std::polar(1.0, p[3]);
        a_ = fifth.real() + seventh.real();
        b_ = fifth.imag() - seventh.imag();
        c_ = fifth.imag() + seventh.imag();
        d_ = seventh.real() - fifth.real();
    }
    // Back-EMF per unit electrical speed (V s/rad) at cos(6 theta) = c6, sin(6 theta) = s6; times
    // omega when `psi_f` is omega psi_f.
    Complex at(double c6, double s6, double psi_f) const { return {psi_f * (a_ * c6 + b_ * s6), psi_f * (c_ * c6 + d_ * s6)}; }

private:
    double a_ = 0.0, b_ = 0.0, c_ = 0.0, d_ = 0.0;
};

// The back-EMF over n rows, e^{j 6 theta} from the logged angle's cosine and sine by three squarings
// and a product.
MHB_ROW_KERNEL void add_emf(const EmfPhasors& emf, Eigen::Index n, const double* __restrict cos_theta, const double* __restrict sin_theta,
                            const double* __restrict omega, const double* __restrict psi_f, double* __restrict u_d,
                            double* __restrict u_q) {
    for (Eigen::Index k = 0; k < n; ++k) {
        const double c1 = cos_theta[k], s1 = sin_theta[k];
        const double c2 = c1 * c1 - s1 * s1, s2 = 2.0 * c1 * s1;
        const double c4 = c2 * c2 - s2 * s2, s4 = 2.0 * c2 * s2;
        const double c6 = c4 * c2 - s4 * s2, s6 = s4 * c2 + c4 * s2;
        const Complex e = emf.at(c6, s6, omega[k] * psi_f[k]);
        u_d[k] += e.real();
        u_q[k] += e.imag();
    }
}

class FluxHarmonic final : public Effect {
public:
    explicit FluxHarmonic(const ParameterSet& p) : Effect("flux_harmonic", p) {}

    Complex plant_flux_ripple(double theta, double psi_f) const override { return ripple_flux(values().data(), theta, psi_f); }
    Complex plant_emf_ripple(double theta, double psi_f) const override {
        return EmfPhasors(values().data()).at(std::cos(6.0 * theta), std::sin(6.0 * theta), psi_f);
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::MachineVoltage); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    bool model_linear_in(std::size_t k) const override { return k == 0 || k == 2; }  // the amplitudes, not the phases
    std::vector<int> angle_orders() const override { return {6}; }  // the 5th and 7th both turn at 6 theta in the rotor frame
    std::vector<std::string> model_columns() const override { return {"theta_e"}; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        add_emf(EmfPhasors(p), s.size(), s.cos_theta.data(), s.sin_theta.data(), s.omega.data(), s.psi_f.data(), s.u_d.data(), s.u_q.data());
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

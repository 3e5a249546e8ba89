// Magnetic saturation and cross-saturation. Model side: the flux linkages of the base model plus the
// derivatives of a polynomial magnetic co-energy
//   W = k_d2 i_d^3/3 + k_d3 i_d^4/4 + k_q3 i_q^4/4 + k_q5 i_q^6/6
//       + k_dq1 i_d i_q^2/2 + k_dq2 i_d^2 i_q^2/2 + k_dq3 i_d i_q^4/4,
//   Delta psi_d = k_d2 i_d^2 + k_d3 i_d^3 + k_dq1 i_q^2/2 + k_dq2 i_d i_q^2 + k_dq3 i_q^4/4,
//   Delta psi_q = k_q3 i_q^3 + k_q5 i_q^5 + k_dq1 i_d i_q + k_dq2 i_d^2 i_q + k_dq3 i_d i_q^3,
// which keeps the machine reciprocal (d psi_d/d i_q = d psi_q/d i_d) and is linear in its coefficients.
// The terms are the lowest orders that respect the symmetry of a PM machine (psi_q odd in i_q, psi_d
// even in i_q); the fifth-order q terms are what a strongly saturating q axis needs.
// Plant side: the same polynomial, or a measured flux map (`flux_map`, a CSV path) that then replaces
// the whole flux model of the plant (Ld, Lq and psi_f of the motor are used only by the controller).
#include <fmt/format.h>

#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/machine/flux_models.hpp"

namespace mhb::pmsm {
namespace {

class Saturation final : public Effect {
public:
    explicit Saturation(const ParameterSet& p) : Effect("saturation", p) {}

    std::unique_ptr<FluxModel> plant_flux_model(const MotorParameters& motor,
                                                const std::filesystem::path& base_directory) const override {
        const auto& map = settings().text("flux_map");
        if (!map.empty()) {
            const std::filesystem::path path = std::filesystem::path(map).is_absolute() ? std::filesystem::path(map) : base_directory / map;
            return std::make_unique<FluxMap>(FluxMap::read(path, motor.psi_f));
        }
        return std::make_unique<PolynomialFlux>(motor.ld, motor.lq, values());
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::FluxLinkage); }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Additive; }
    bool model_linear_in(std::size_t) const override { return true; }
    void model(ModelStage, const double* k, ModelState& s) const override {
        for (Eigen::Index j = 0; j < s.psi_d.size(); ++j) {
            const Complex change = polynomial_flux_change(k, s.i_d[j], s.i_q[j]);
            s.psi_d[j] += change.real();
            s.psi_q[j] += change.imag();
        }
    }
};

const bool registered = register_effect({
    "saturation",
    "Saturation and cross-saturation: polynomial co-energy model, or a measured flux map on the plant",
    {ParameterSpec::real("k_d2", 0.0, -1.0, 1.0, "d flux term k_d2 i_d^2 (magnet-side asymmetry)", "Wb/A^2"),
     ParameterSpec::real("k_d3", 0.0, -1.0, 1.0, "d self-saturation k_d3 i_d^3", "Wb/A^3"),
     ParameterSpec::real("k_q3", 0.0, -1.0, 1.0, "q self-saturation k_q3 i_q^3", "Wb/A^3"),
     ParameterSpec::real("k_q5", 0.0, -1.0, 1.0, "q self-saturation k_q5 i_q^5", "Wb/A^5"),
     ParameterSpec::real("k_dq1", 0.0, -1.0, 1.0, "cross-saturation, psi_d += k i_q^2/2, psi_q += k i_d i_q", "Wb/A^2"),
     ParameterSpec::real("k_dq2", 0.0, -1.0, 1.0, "cross-saturation, psi_d += k i_d i_q^2, psi_q += k i_d^2 i_q", "Wb/A^3"),
     ParameterSpec::real("k_dq3", 0.0, -1.0, 1.0, "cross-saturation, psi_d += k i_q^4/4, psi_q += k i_d i_q^3", "Wb/A^4"),
     ParameterSpec::text("flux_map", "", "plant only: CSV flux map (i_d_A, i_q_A, psi_d_Vs, psi_q_Vs) replacing the plant's flux model")},
    [](const ParameterSet& p) { return std::make_unique<Saturation>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

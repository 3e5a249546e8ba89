// Magnet temperature: psi_f(T) = psi_f20 (1 + alpha (T - 20 °C)); NdFeB alpha ~ -0.09..-0.12 %/K,
// SmCo -0.03..-0.04 %/K. Its residual is ~ omega Delta T on u_q only.
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {
namespace {

class PsiThermal final : public Effect {
public:
    explicit PsiThermal(const ParameterSet& p) : Effect("psi_thermal", p) {}

    void plant_coefficients(const PlantConditions& c, double&, double& psi_f) const override {
        psi_f *= 1.0 + values()[0] * (c.temp_magnet - reference_temperature);
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::Coefficients); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    bool model_linear_in(std::size_t) const override { return true; }
    std::vector<int> angle_orders() const override { return {}; }
    std::vector<std::string> model_columns() const override { return {"temp_magnet"}; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        s.psi_f *= 1.0 + p[0] * (s.temp_magnet - reference_temperature);
    }
};

const bool registered = register_effect({
    "psi_thermal",
    "Magnet flux falling with magnet temperature (needs temp_magnet)",
    {ParameterSpec::real("alpha", -0.001, -0.0025, -0.0002, "temperature coefficient of the remanence", "1/K")},
    [](const ParameterSet& p) { return std::make_unique<PsiThermal>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

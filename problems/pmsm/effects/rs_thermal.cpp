// Winding temperature: R_s(T) = R_s20 (1 + alpha (T - 20 °C)), alpha = 0.00393/K for copper. The
// base parameter R_s is then the resistance at 20 °C and the residual it removes is ~ i Delta T.
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {
namespace {

class RsThermal final : public Effect {
public:
    explicit RsThermal(const ParameterSet& p) : Effect("rs_thermal", p) {}

    void plant_coefficients(const PlantConditions& c, double& rs, double&) const override {
        rs *= 1.0 + values()[0] * (c.temp_winding - reference_temperature);
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::Coefficients); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    bool model_linear_in(std::size_t) const override { return true; }
    std::vector<int> angle_orders() const override { return {}; }
    std::vector<std::string> model_columns() const override { return {"temp_winding"}; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        s.rs *= 1.0 + p[0] * (s.temp_winding - reference_temperature);
    }
    // Annealed copper's coefficient at 20 °C (IEC 60028); the range's 0.0035-0.0045 is copper's and
    // aluminium's (0.00403) spread with the winding's mean temperature against the logged one.
    std::optional<double> material_value(std::size_t) const override { return 0.00393; }
};

const bool registered = register_effect({
    "rs_thermal",
    "Stator resistance rising with winding temperature (needs temp_winding)",
    {ParameterSpec::real("alpha", 0.00393, 0.0035, 0.0045, "temperature coefficient of the winding resistance", "1/K")},
    [](const ParameterSet& p) { return std::make_unique<RsThermal>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

// A constant voltage offset per axis between the logged reference and what reaches the inverter
// (e.g. an uncompensated measurement or modulation offset). It leaves a constant residual.
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {
namespace {

class VoltageOffset final : public Effect {
public:
    explicit VoltageOffset(const ParameterSet& p) : Effect("voltage_offset", p) {}

    Complex plant_command_shortfall() const override { return {values()[0], values()[1]}; }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::LoggedVoltage); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Additive; }
    bool model_linear_in(std::size_t) const override { return true; }
    std::vector<int> angle_orders() const override { return {}; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        s.u_d += p[0];
        s.u_q += p[1];
    }
};

const bool registered = register_effect({
    "voltage_offset",
    "Constant d and q voltage offsets between the logged reference and the inverter input",
    {ParameterSpec::real("u_d", 0.01, -2.0, 2.0, "d-axis offset (logged minus applied)", "V"),
     ParameterSpec::real("u_q", 0.0, -2.0, 2.0, "q-axis offset (logged minus applied)", "V")},
    [](const ParameterSet& p) { return std::make_unique<VoltageOffset>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

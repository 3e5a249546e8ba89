// Encoder (angle) offset: the controller's frame leads the rotor frame by delta, so it measures the
// currents rotated by -delta and its voltage reference lands rotated by +delta. In steady state
// Delta u_d ~ omega psi_f delta: a d-axis residual proportional to speed, independent of current.
#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {
namespace {

void rotate(Eigen::ArrayXd& d, Eigen::ArrayXd& q, double angle) {
    const Complex turn = std::polar(1.0, angle);
    turn_rows(turn.real(), turn.imag(), d.size(), d.data(), q.data());
}

class EncoderOffset final : public Effect {
public:
    explicit EncoderOffset(const ParameterSet& p) : Effect("encoder_offset", p) {}

    double plant_angle_offset() const override { return values()[0]; }

    unsigned model_stages() const override { return ModelStage::SensorAngle | ModelStage::ControllerFrame; }
    bool model_changes_inputs(ModelStage) const override { return false; }
    bool is_size(std::size_t) const override { return true; }
    std::vector<int> angle_orders() const override { return {}; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    void model(ModelStage stage, const double* p, ModelState& s) const override {
        if (stage == ModelStage::SensorAngle) {
            rotate(s.i_d, s.i_q, p[0]);
            s.rotate_angle(-p[0]);
        } else {
            rotate(s.u_d, s.u_q, -p[0]);
        }
    }
};

const bool registered = register_effect({
    "encoder_offset",
    "Angle offset of the position sensor: measured minus true electrical angle",
    {ParameterSpec::real("offset", 0.0174533, -0.2, 0.2, "electrical angle offset (1 degree = 0.01745)", "rad")},
    [](const ParameterSet& p) { return std::make_unique<EncoderOffset>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

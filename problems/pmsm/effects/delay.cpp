// Computation and PWM delay: the inverter applies the controller's rotating voltage vector tau late
// (one period of computation plus half a period of PWM hold: tau = 1.5 T_s is usual). In steady state
// the applied vector is the command rotated back by omega tau, so the logged command is
// e^{j omega tau} times what the machine needs: Delta u_d ~ -omega tau u_q, Delta u_q ~ +omega tau u_d.
#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/effects/row_memo.hpp"
#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {
namespace {

// e^{j omega tau} of a block's rows (RowMemo): a sine and cosine a row in each of the affine split's
// lanes and the Jacobian's predictions was 4.5 % of a diagnosis of 10^5 rows.
thread_local RowMemo<Complex> turns;

// u turned by each row's own e^{j omega tau}, as turn_rows (model/row_kernel.hpp) turns all rows by one angle.
MHB_ROW_KERNEL void turn_rows(Eigen::Index n, const Complex* __restrict turn, double* __restrict u_d, double* __restrict u_q) {
    for (Eigen::Index k = 0; k < n; ++k) {
        const double c = turn[k].real(), s = turn[k].imag(), d = u_d[k], q = u_q[k];
        u_d[k] = c * d - s * q;
        u_q[k] = c * q + s * d;
    }
}

class Delay final : public Effect {
public:
    explicit Delay(const ParameterSet& p) : Effect("delay", p) {}

    double plant_delay() const override { return values()[0]; }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::Delay); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    bool is_size(std::size_t) const override { return true; }
    std::vector<int> angle_orders() const override { return {}; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Linear; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        // The affine split runs this stage in each of its five lanes at the same angles.
        const Complex* turn = turns.of(p[0], s.u_d.size(), [&](Eigen::Index k) { return s.omega[k] * p[0]; },
                                       [](double angle) { return std::polar(1.0, angle); });
        turn_rows(s.u_d.size(), turn, s.u_d.data(), s.u_q.data());
    }
};

const bool registered = register_effect({
    "delay",
    "Computation and PWM delay between the voltage reference and the inverter output",
    {ParameterSpec::real("tau", 1.5e-4, 0.0, 1e-3, "delay of the applied voltage vector", "s")},
    [](const ParameterSet& p) { return std::make_unique<Delay>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

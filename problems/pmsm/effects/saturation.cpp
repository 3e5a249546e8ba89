// Magnetic saturation and cross-saturation. Model side: the flux linkages of the base model plus the
// gradient of a co-energy in per-unit currents (machine/flux_models.hpp, CoenergySaturation): q-axis
// self-saturation through a knee, cross-saturation as a power law, and the magnet-side asymmetry of
// the d axis. Reciprocal by construction; the coefficients are per unit of
// the log's flux and the currents per unit of its largest current (Effect::scale()), so their ranges
// mean the same on any machine; the fitted machine must keep positive incremental inductances over
// the logged currents (implausible_reason). docs/effects.md, "The saturation effect", says why this
// law and what it replaced.
// Plant side: the same law at the drive's scale (its current limit and magnet flux), or a measured flux map (`flux_map`, a CSV path) that
// then replaces the whole flux model of the plant (Ld, Lq and psi_f of the motor are used only by the
// controller).
#include <cmath>

#include <fmt/format.h>

#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/effects/row_memo.hpp"
#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {
namespace {

// pow(|y|, V) and the knee's loss of a block's rows (RowMemo): the Jacobian of a fit predicts a block
// up to nine times at one exponent and knee (the point, each linear coefficient, the other's two
// differences), and pow was most of the effect's cost (a fifth of a long log's diagnosis).
thread_local RowMemo<double> powers, knee_losses;

// The law's change of the fluxes over n rows, given each row's pow and knee loss.
MHB_ROW_KERNEL void add_flux_change(const CoenergySaturation& l, Eigen::Index n, const double* __restrict i_d, const double* __restrict i_q,
                                    const double* __restrict yv, const double* __restrict loss, double* __restrict psi_d,
                                    double* __restrict psi_q) {
    for (Eigen::Index j = 0; j < n; ++j) {
        const Complex change = l.flux_change(i_d[j], i_q[j], yv[j], loss[j]);
        psi_d[j] += change.real();
        psi_q[j] += change.imag();
    }
}

class Saturation final : public Effect {
public:
    explicit Saturation(const ParameterSet& p) : Effect("saturation", p) {}

    std::unique_ptr<FluxModel> plant_flux_model(const MotorParameters& motor, const OperatingScale& plant,
                                                const std::filesystem::path& base_directory) const override {
        const auto& map = settings().text("flux_map");
        if (!map.empty()) {
            const std::filesystem::path path = std::filesystem::path(map).is_absolute() ? std::filesystem::path(map) : base_directory / map;
            return std::make_unique<FluxMap>(FluxMap::read(path, motor.psi_f));
        }
        return std::make_unique<CoenergySaturatedFlux>(motor.ld, motor.lq, CoenergySaturation::from(values().data(), plant.current, plant.flux));
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::FluxLinkage); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Additive; }
    // The coefficients; not the knee and the exponent.
    bool model_linear_in(std::size_t k) const override { return k != 1 && k != 3; }
    void model(ModelStage, const double* p, ModelState& s) const override {
        const CoenergySaturation l = law(p);
        const Eigen::Index n = s.psi_d.size();
        const double* yv = powers.of(l.v, n, [&](Eigen::Index j) { return l.cross_base(s.i_q[j]); },
                                     [&](double base) { return std::pow(base, l.v); });
        const double* loss = knee_losses.of(l.knee, n, [&](Eigen::Index j) { return s.i_q[j] / l.base_current; },
                                            [&](double y) { return CoenergySaturation::knee_loss(y, l.knee); });
        add_flux_change(l, n, s.i_d.data(), s.i_q.data(), yv, loss, s.psi_d.data(), s.psi_q.data());
    }

    // q self-saturation with its knee, cross-saturation with its exponent, the d axis's asymmetry,
    // the second-order cross term.
    std::vector<std::vector<std::size_t>> law_terms() const override { return {{0, 1}, {2, 3}, {4}, {5}}; }

    // Fitted directly to the Baldor machine's measured map over i_d from -12 to 0 A and |i_q| up to
    // 24 A, the law leaves 1.9 % of the flux linkage rms (docs/effects.md, "The Baldor study").
    double law_accuracy() const override { return 0.02; }
    std::vector<int> angle_orders() const override { return {}; }  // the fluxes follow the rotor-frame currents alone

    // The current i(psi) is convex where the incremental inductance falls with the current, so over
    // a carrier period's flux ripple (its midpoint is what the sample at the carrier peak reads) the
    // mean current exceeds the sample by half i'' times the flux's variance: -(dL/di) di_pp^2 / (24 L)
    // for a triangular ripple. The voltage drop is Rs times the mean; the fluxes, at the midpoint,
    // are moved much less (tests/pmsm_saturation_test.cpp). Its size needs the ripple, which only
    // the inverter's V_dc and f_sw give, so the sentence gives the formula.
    UnseenBias unseen_bias(const double* /*base*/) const override {
        return {"with saturating iron a current sampled at the carrier peak is the midpoint of the ripple in flux, not the period's "
                "mean current: Rs reads high by about (-(dL/di) / L) di_pp^2 / (24 |i|) (di_pp the ripple peak to peak, L the incremental "
                "inductance along the current), which falls with the carrier frequency squared; the flux terms, which see the midpoint, "
                "much less; the Rs interval does not hold it",
                {true, false, false, false}};
    }

    bool range_end_implausible(std::size_t k) const override { return k != 1 && k != 3; }
    std::string range_end_meaning(std::size_t k, bool upper) const override {
        switch (k) {
        case 1:
            return upper ? "the knee lies beyond the logged currents, which show only its onset"
                         : "the knee lies below the logged currents: the q inductance is simply lower, which L_q already is";
        case 3: return "cross-saturation rising more steeply with |i_q| than this log resolves";
        default: return "an inductance change as large as the log's whole flux per unit of its current";
        }
    }

    std::string implausible_reason(const double* p, const double* base, const Eigen::ArrayXd& i_d,
                                   const Eigen::ArrayXd& i_q) const override {
        const CoenergySaturation l = law(p);
        for (Eigen::Index j = 0; j < i_d.size(); ++j) {
            Inductance m = l.inductance_change(i_d[j], i_q[j]);
            m[0] += base[1];
            m[3] += base[2];
            // Positive definite: a stored energy that rises with every current change.
            if (m[0] > 0.0 && m[3] > 0.0 && m[0] * m[3] - m[1] * m[2] > 0.0) continue;
            return fmt::format("the fitted machine's incremental inductance is not positive definite at i_d = {:.4g} A, "
                               "i_q = {:.4g} A (L_dd {:.4g} H, L_qq {:.4g} H, L_dq {:.4g} H): its flux would fall as its current rises",
                               i_d[j], i_q[j], m[0], m[3], m[1]);
        }
        return {};
    }

private:
    CoenergySaturation law(const double* p) const { return CoenergySaturation::from(p, scale().current, scale().flux); }
};

const bool registered = register_effect({
    "saturation",
    "Saturation and cross-saturation: a reciprocal power-law co-energy per unit of the log's current and flux, or a measured flux map on the plant",
    {ParameterSpec::real("q_self", 0.0, 0.0, 5.0, "q self-saturation: the fall of the q incremental inductance past the knee",
                         "per unit of Psi_b / I_b"),
     ParameterSpec::real("q_knee", 0.5, 0.02, 5.0, "the q axis's knee current", "per unit of I_b"),
     ParameterSpec::real("cross", 0.0, -5.0, 5.0, "cross-saturation: psi_d falls by cross Psi_b |y|^(V+2)/(V+2), psi_q by cross Psi_b x |y|^V y",
                         "per unit of Psi_b"),
     ParameterSpec::real("cross_exponent", 2.0, 1.0, 12.0, "V, how the cross-saturation grows with |i_q|", ""),
     ParameterSpec::real("d_even", 0.0, -5.0, 5.0, "magnet-side asymmetry of the d axis: psi_d rises by d_even Psi_b x^2", "per unit of Psi_b"),
     ParameterSpec::real("cross_square", 0.0, -5.0, 5.0,
                         "cross-saturation to second order: psi_d falls by cross_square Psi_b y^2/2, psi_q by cross_square Psi_b x y (negative: "
                         "psi_d rises, as where the q flux saturates a rotor bridge)",
                         "per unit of Psi_b"),
     ParameterSpec::text("flux_map", "", "plant only: CSV flux map (i_d_A, i_q_A, psi_d_Vs, psi_q_Vs) replacing the plant's flux model")},
    [](const ParameterSet& p) { return std::make_unique<Saturation>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

// Inverter dead time and device voltage drop. Each phase loses V_dt in the direction of its current,
// V_dt = t_dead f_sw V_dc + V_device; near zero current the loss turns over a band, i / sqrt(i^2 + b^2):
// each leg's loss follows the current at its switching edges, which the carrier's ripple moves off
// the sampled current by an amount that changes with the duty cycles, so over a drive's operating
// points the turn is soft with a slow tail (docs/effects.md, "deadtime", measured against a linear
// band and tanh). In dq this is (4/pi) V_dt i/|i| plus a 6 omega ripple: an "extra resistance" that
// is largest at small current.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {
namespace {

// A phase current's direction: a sign, or turning through zero over a band (i / sqrt(i^2 + b^2)).
// Branch-free, so that the model's loop over a block of rows vectorises.
struct HardSign {
    double operator()(double i) const { return static_cast<double>(i > 0.0) - static_cast<double>(i < 0.0); }
};
struct BandSign {
    double per_ampere;
    double operator()(double i) const {
        const double x = i * per_ampere;
        return x / std::sqrt(1.0 + x * x);
    }
};
// f called with the direction a band asks for (0: a sign).
template <class F>
decltype(auto) with_sign(double band, F&& f) {
    return band > 0.0 ? f(BandSign{1.0 / band}) : f(HardSign{});
}

// Voltage lost at the terminals, in the rotor frame, from the three phase currents: (cos_theta,
// sin_theta) = e^{j theta}; i_d, i_q the rotor-frame currents. Written in real arithmetic because
// complex products keep a NaN branch that stops the model's loop from vectorising.
template <class Sign>
[[gnu::always_inline]] inline Complex terminal_loss(double voltage, Sign sign, double cos_theta, double sin_theta, double i_d, double i_q) {
    const double alpha = i_d * cos_theta - i_q * sin_theta, beta = i_d * sin_theta + i_q * cos_theta;
    const double half_root3 = 0.5 * std::numbers::sqrt3;
    const double a = sign(alpha), b = sign(-0.5 * alpha + half_root3 * beta), c = sign(-0.5 * alpha - half_root3 * beta);
    // Clarke of the phase losses, then into the rotor frame.
    const double loss_alpha = voltage * (2.0 * a - b - c) / 3.0, loss_beta = voltage * (b - c) / std::numbers::sqrt3;
    return {loss_alpha * cos_theta + loss_beta * sin_theta, loss_beta * cos_theta - loss_alpha * sin_theta};
}

template <class Sign>
[[gnu::always_inline]] inline void add_loss_rows(double voltage, Sign sign, Eigen::Index n, const double* __restrict cos_theta,
                                                 const double* __restrict sin_theta, const double* __restrict i_d,
                                                 const double* __restrict i_q, double* __restrict u_d, double* __restrict u_q) {
    for (Eigen::Index k = 0; k < n; ++k) {
        const Complex l = terminal_loss(voltage, sign, cos_theta[k], sin_theta[k], i_d[k], i_q[k]);
        u_d[k] += l.real();
        u_q[k] += l.imag();
    }
}

// The loss over a block's rows (a fit's Jacobian runs it for every linear column of every block); with
// AVX2 the band's square roots and divisions take four rows at a time.
MHB_ROW_KERNEL void add_band_loss(double voltage, double per_ampere, Eigen::Index n, const double* cos_theta, const double* sin_theta,
                                  const double* i_d, const double* i_q, double* u_d, double* u_q) {
    add_loss_rows(voltage, BandSign{per_ampere}, n, cos_theta, sin_theta, i_d, i_q, u_d, u_q);
}
MHB_ROW_KERNEL void add_sign_loss(double voltage, Eigen::Index n, const double* cos_theta, const double* sin_theta, const double* i_d,
                                  const double* i_q, double* u_d, double* u_q) {
    add_loss_rows(voltage, HardSign{}, n, cos_theta, sin_theta, i_d, i_q, u_d, u_q);
}

void add_terminal_loss(double voltage, double band, ModelState& s) {
    if (band > 0.0)
        add_band_loss(voltage, 1.0 / band, s.size(), s.cos_theta.data(), s.sin_theta.data(), s.i_d.data(), s.i_q.data(), s.u_d.data(),
                      s.u_q.data());
    else
        add_sign_loss(voltage, s.size(), s.cos_theta.data(), s.sin_theta.data(), s.i_d.data(), s.i_q.data(), s.u_d.data(), s.u_q.data());
}

inline constexpr double max_band_fraction = 0.2;

class DeadTime final : public Effect {
public:
    explicit DeadTime(const ParameterSet& p) : Effect("deadtime", p) {}

    Complex plant_inverter_loss(double theta, Complex i) const override {
        return with_sign(values()[1], [&](auto sign) { return terminal_loss(values()[0], sign, std::cos(theta), std::sin(theta), i.real(), i.imag()); });
    }

    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::InverterError); }
    bool model_changes_inputs(ModelStage) const override { return false; }
    BaseDependence model_base_dependence(ModelStage) const override { return BaseDependence::Additive; }
    bool model_linear_in(std::size_t k) const override { return k == 0; }  // the voltage, not the band
    // The loss follows each phase current's sign: a six-step wave in the stator frame, whose
    // harmonics in the rotor frame are the multiples of 6.
    std::vector<int> angle_orders() const override {
        std::vector<int> out;
        for (int k = 6; k <= 60; k += 6) out.push_back(k);
        return out;
    }

    // A band over a large part of the logged current makes the loss proportional to the current: a
    // resistance, which R_s already is. The band's physical causes (ripple, snubber charge) are a
    // small fraction of the current the inverter is rated for, whatever its size: on a traction
    // machine the PWM ripple (V_dc T / L) alone is 6-14 A, beyond the declared 10 A, so the log's
    // fraction sets the end on both sides of the declaration.
    void plausible_range(std::size_t k, double&, double& hi) const override {
        if (k == 1) hi = max_band_fraction * scale().current;
    }
    std::string range_end_meaning(std::size_t k, bool upper) const override {
        if (k != 1 || !upper) return {};
        return fmt::format("a band this wide ({:g} of the largest logged current) acts as a resistance: it is confounded with Rs",
                           max_band_fraction);
    }
    // Each turn-on edge comes t_d late whatever the current's sign, so every pulse's centre moves by
    // t_d / 2 and the current sampled at the carrier peak is its period average plus t_d / 2 of
    // L^-1 u: the fit then sees R / (1 + R t_d / (2 L)), and the flux terms likewise. A shift of
    // half a microsecond is far below any log's delay limit, so only the inverter's settings say it.
    UnseenBias unseen_bias(const double* base) const override {
        const double per_microsecond = 100.0 * 0.5e-6 * base[0] / std::min(base[1], base[2]);
        if (!(per_microsecond > 0.0) || !std::isfinite(per_microsecond)) return {};  // an implausible fit (L <= 0) says nothing
        return {fmt::format("dead time shifts each PWM pulse by half the dead time t_d, so currents sampled at the carrier peak are not "
                            "their period averages: Rs, Ld, Lq and psi_f read low by about Rs t_d / (2 L), up to {:.2g} % per microsecond "
                            "of t_d here (t_d = deadtime.voltage / (f_sw V_dc) less the devices' share); the intervals do not hold it",
                            per_microsecond)};
    }

    void model(ModelStage, const double* p, ModelState& s) const override {
        if (s.theta.size() > 0) {
            add_terminal_loss(p[0], p[1], s);
            return;
        }
        // Without the angle only the fundamental is known: (4/pi) V_dt along the current.
        const double gain = 4.0 / std::numbers::pi * p[0];
        for (Eigen::Index k = 0; k < s.u_d.size(); ++k) {
            const double magnitude = std::hypot(s.i_d[k], s.i_q[k]);
            if (magnitude == 0.0) continue;
            s.u_d[k] += gain * s.i_d[k] / magnitude;
            s.u_q[k] += gain * s.i_q[k] / magnitude;
        }
    }
};

const bool registered = register_effect({
    "deadtime",
    "Inverter dead time and device drop: each phase loses V_dt against its current",
    {ParameterSpec::real("voltage", 0.28, 0.0, 10.0, "per-phase voltage error t_dead f_sw V_dc + V_device", "V"),
     ParameterSpec::real("current_band", 0.0, 0.0, 10.0,
                         "phase current at which the error is 1/sqrt(2) of V_dt: it turns as i/sqrt(i^2+b^2) (0: a sign)", "A")},
    [](const ParameterSet& p) { return std::make_unique<DeadTime>(p); },
});

}  // namespace
}  // namespace mhb::pmsm

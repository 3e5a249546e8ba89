#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "framework/random.hpp"
#include "problems/pmsm/machine/power_law_flux.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {

// Three machines: the fit to the Baldor PM-SyRM map (per unit of 26 A, 1.3117 Wb), a synchronous
// reluctance machine without magnet in the style of Hinkkanen 2017, and an interior-magnet machine
// whose bridge saturates hard.
std::vector<PowerLawSaturation> parameter_sets() {
    return {
        PowerLawSaturation::from_values({0.15489, 1.5746, 2.6966, 0.26345, 0.58343, 5.0877, 6.5055, 0.98992, 1.8001,
                                         0.46026, 26.246, 8.6489, 1.6203, 0.082294},
                                        26.0, 1.3117),
        PowerLawSaturation::from_values({2.0, 3.0, 5.0, 0.4, 0.8, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0}, 15.5, 0.9),
        PowerLawSaturation::from_values({1.5, 0.5, 3.0, 0.6, 0.5, 2.0, 0.3, 0.5, 1.0, 0.6, 5.0, 2.0, 2.0, 0.2}, 400.0, 0.12),
    };
}

// Currents over the range the parameters are stated for: i_d within +-0.75, i_q within +-1 base
// current (the Baldor map spans 20 A and 26 A).
std::vector<Complex> current_grid(double base_current) {
    std::vector<Complex> grid;
    for (int a = -15; a <= 15; ++a)
        for (int b = -20; b <= 20; ++b) grid.emplace_back(0.05 * a * base_current, 0.05 * b * base_current);
    return grid;
}

}  // namespace

TEST_CASE("power-law flux: incremental inductances are the flux's derivatives and reciprocal", "[pmsm][power_law_flux]") {
    for (const auto& p : parameter_sets()) {
        const PowerLawFlux model(p);
        const double psi_f = model.magnet_flux(), h = 1e-6 * p.base_current;
        for (const Complex i : current_grid(p.base_current)) {
            const auto l = model.incremental_inductance(i);
            const Complex by_d = (model.flux(i + Complex{h, 0.0}, psi_f) - model.flux(i - Complex{h, 0.0}, psi_f)) / (2.0 * h);
            const Complex by_q = (model.flux(i + Complex{0.0, h}, psi_f) - model.flux(i - Complex{0.0, h}, psi_f)) / (2.0 * h);
            const double scale = std::abs(l[0]) + std::abs(l[3]);
            // 1e-5: at i = 0 an exponent of 1 puts a kink in dL/di, which central differences straddle.
            CHECK(std::abs(by_d.real() - l[0]) < 1e-5 * scale);
            CHECK(std::abs(by_q.real() - l[1]) < 1e-5 * scale);
            CHECK(std::abs(by_d.imag() - l[2]) < 1e-5 * scale);
            CHECK(std::abs(by_q.imag() - l[3]) < 1e-5 * scale);
            // Reciprocity measured on the flux itself, not only on the returned matrix.
            CHECK(std::abs(by_q.real() - by_d.imag()) < 1e-5 * scale);
        }
    }
}

TEST_CASE("power-law flux: positive definite incremental inductance and monotone flux", "[pmsm][power_law_flux]") {
    for (const auto& p : parameter_sets()) {
        const PowerLawFlux model(p);
        const double psi_f = model.magnet_flux(), step = 0.05 * p.base_current;
        for (const Complex i : current_grid(p.base_current)) {
            const auto l = model.incremental_inductance(i);
            CHECK(l[0] > 0.0);
            CHECK(l[0] * l[3] - l[1] * l[2] > 0.0);
            // Each flux grows with its own current, and the pair with the pair (a monotone map).
            const Complex psi = model.flux(i, psi_f);
            CHECK(model.flux(i + Complex{step, 0.0}, psi_f).real() > psi.real());
            CHECK(model.flux(i + Complex{0.0, step}, psi_f).imag() > psi.imag());
            const Complex di{0.6 * step, -0.8 * step}, dpsi = model.flux(i + di, psi_f) - psi;
            CHECK(dpsi.real() * di.real() + dpsi.imag() * di.imag() > 0.0);
        }
    }
}

TEST_CASE("power-law flux: psi(i) and i(psi) invert each other", "[pmsm][power_law_flux]") {
    Rng rng(11);
    for (const auto& p : parameter_sets()) {
        const PowerLawFlux model(p);
        const double psi_f = model.magnet_flux();
        for (int k = 0; k < 300; ++k) {
            // Beyond the stated range too, where the power laws are steep and Newton must be damped.
            const Complex i{rng.uniform(-1.2, 1.2) * p.base_current, rng.uniform(-1.5, 1.5) * p.base_current};
            const Complex psi = model.flux(i, psi_f);
            CHECK(std::abs(model.current(psi, psi_f, {}) - i) < 1e-9 * p.base_current);
            // The generic damped Newton of FluxModel from a zero guess agrees.
            CHECK(std::abs(model.FluxModel::current(psi, psi_f, {}) - i) < 1e-8 * p.base_current);
        }
        // A magnet flux other than the model's own shifts psi_d only.
        const Complex i{0.3 * p.base_current, -0.4 * p.base_current};
        const Complex shifted = model.flux(i, psi_f + 0.01), own = model.flux(i, psi_f);
        CHECK(shifted.real() - own.real() == Approx(0.01).epsilon(1e-9));
        CHECK(shifted.imag() == own.imag());
        CHECK(std::abs(model.current(shifted, psi_f + 0.01, {}) - i) < 1e-9 * p.base_current);
    }
}

TEST_CASE("power-law flux: the same dimensionless parameters give the same shape at any current scale", "[pmsm][power_law_flux]") {
    for (const auto& p : parameter_sets()) {
        auto large = p;
        large.base_current *= 1000.0;
        const PowerLawFlux small_machine(p), large_machine(large);
        CHECK(large_machine.magnet_flux() == Approx(small_machine.magnet_flux()).epsilon(1e-12));
        for (const Complex i : current_grid(p.base_current)) {
            const Complex psi = small_machine.flux(i, small_machine.magnet_flux());
            const Complex psi_large = large_machine.flux(1000.0 * i, large_machine.magnet_flux());
            CHECK(std::abs(psi_large - psi) < 1e-12 * p.base_flux);
            const auto l = small_machine.incremental_inductance(i), l_large = large_machine.incremental_inductance(1000.0 * i);
            for (int k = 0; k < 4; ++k) CHECK(1000.0 * l_large[k] == Approx(l[k]).margin(1e-12 * (l[0] + l[3])));
        }
    }
}

TEST_CASE("power-law flux: inadmissible parameters are refused and non-convex ones detected", "[pmsm][power_law_flux]") {
    auto p = parameter_sets()[1];
    p.qq = -0.1;
    CHECK_THROWS_AS(PowerLawFlux(p), std::invalid_argument);
    p = parameter_sets()[1];
    p.q0 = 0.0;
    CHECK_FALSE(p.inadmissible_reason().empty());
    // The cross-saturation term alone is not convex: made to dominate, it turns the incremental
    // inductance indefinite somewhere in the range, which is what the fit refuses.
    p = parameter_sets()[1];
    p.dq = 200.0;
    const PowerLawFlux model(p);
    bool indefinite = false;
    for (double x = -1.0; x <= 1.0; x += 0.1)
        for (double y = -1.0; y <= 1.0; y += 0.1) {
            const auto h = model.inverse_inductance({x * p.base_flux, y * p.base_flux});
            indefinite = indefinite || h[0] * h[3] - h[1] * h[2] <= 0.0;
        }
    CHECK(indefinite);
}

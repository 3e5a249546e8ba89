// The dead-time effect against the device plant, which switches each leg with its dead time instead
// of applying the effect's averaged loss: what the effect's law follows, and the bias it states that
// no log shows (Effect::unseen_bias).
#include <catch2/catch.hpp>

#include <filesystem>

#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

// The device study's drive with a dead time and no noise, fitted with base+deadtime.
Eigen::Vector4d relative_errors_with_dead_time(double dead_time) {
    return noise_free_device_errors("base+deadtime", [&](DeviceSettings& device) { device.inverter.dead_time = dead_time; });
}

}  // namespace

TEST_CASE("dead time biases the base parameters by the pulse shift the effect states", "[pmsm][deadtime]") {
    // Every turn-on edge comes t_d late, so each pulse's centre moves by t_d / 2 and the current
    // sampled at the carrier peak is its period average plus t_d / 2 of L^-1 u: the fit sees
    // R / (1 + R t_d / (2 L)), and psi_f likewise (derived in docs/diagnosis.md, section 4). The
    // plant knows nothing of that formula: it switches the legs. The law's smooth band adds its own
    // share beside the shift: on this servo, whose ripple makes each phase's loss switch within a
    // few milliamperes, the band's slow tail reads as a little resistance (docs/effects.md,
    // "deadtime"). Measured (2026-11-27): R_s 1.80 and 1.71 times the shift's prediction at 1 and
    // 2 us, psi_f 2.12 and 2.02 times (with a linear band, before: 1.13 and 1.10, 0.89 and 0.90).
    // Both parts grow with t_d, so the errors do, as the statement per microsecond says.
    const double rs = 46.0, l = 0.02025;
    Eigen::Vector4d at_one;
    for (const double dead_time : {1e-6, 2e-6}) {
        INFO("t_d = " << dead_time);
        const double predicted = -rs * dead_time / (2.0 * l);
        const Eigen::Vector4d error = relative_errors_with_dead_time(dead_time);
        for (const int j : {0, 3}) {
            CHECK(error[j] / predicted >= 1.0);
            CHECK(error[j] / predicted <= 2.5);
        }
        if (dead_time == 1e-6) at_one = error;
        else
            for (const int j : {0, 3}) CHECK(error[j] / at_one[j] == Approx(2.0).margin(0.2));
    }
}

TEST_CASE("a fit holding dead time states its pulse-shift bias per microsecond", "[pmsm][deadtime]") {
    ModelFit fit = fit_at("base+deadtime", {46.0, 0.02025, 0.03, 0.04375});
    const auto biases = fit.unseen_biases();
    REQUIRE(biases.size() == 1);
    // R_s / (2 L) per microsecond with the smaller inductance: 46 / 0.0405 * 1e-6 = 0.114 %.
    CHECK(biases.front().text.find("up to 0.11 % per microsecond") != std::string::npos);
    CHECK(biases.front().base == std::array<bool, 4>{true, true, true, true});
    fit.spec = parse_model_spec("base+voltage_offset");
    CHECK(fit.unseen_biases().empty());
}

TEST_CASE("the band's plausible range is the log's fraction on both sides of the declared range", "[pmsm][deadtime]") {
    auto effect = make_effect("deadtime");
    const auto& declared = effect->parameter_specs()[1];
    // The servo's 0.33 A: 0.2 of it ends the plausible range, a band that wide is a resistance.
    effect->set_scale({0.33, 0.05});
    double lo = declared.minimum, hi = declared.maximum;
    effect->plausible_range(1, lo, hi);
    CHECK(hi == Approx(0.066));
    CHECK(effect->range_end_meaning(1, true).find("acts as a resistance") != std::string::npos);
    // A traction machine's 360 A, whose PWM ripple alone is 6-14 A: 72 A, beyond the declared 10 A.
    effect->set_scale({360.0, 0.1});
    lo = declared.minimum, hi = declared.maximum;
    effect->plausible_range(1, lo, hi);
    CHECK(hi == Approx(72.0));
    CHECK(declared.maximum < hi);
    CHECK(effect->range_end_meaning(0, true).empty());
}

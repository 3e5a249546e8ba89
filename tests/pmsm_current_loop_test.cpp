// The drive's current loop between the machine's voltage and the logged reference
// (model/steady_state_model.hpp, loop_response): what the steady-state model passes an effect's angle
// harmonics through once a log states the loop's bandwidth, against the closed form of a first-order
// loop and against the device plant, which switches its legs under a discrete PI controller and
// knows nothing of the formula.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <numbers>
#include <utility>
#include <vector>

#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/model/model_spec.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

TEST_CASE("the loop's response is a first-order low pass without speed or delay, and 1 at zero frequency", "[pmsm][current_loop]") {
    const double alpha = 2.0 * std::numbers::pi * 400.0;
    CHECK(std::abs(loop_response(alpha, 187.5e-6, 0.0, 0.0) - 1.0) < 1e-15);
    // An IMC-tuned PI loop closes to alpha / (s + alpha).
    for (const double omega_h : {-5000.0, -300.0, 100.0, 2513.0, 20000.0}) {
        const std::complex<double> first_order = alpha / std::complex<double>(alpha, omega_h);
        CHECK(std::abs(loop_response(alpha, 0.0, 0.0, omega_h) - first_order) < 1e-12);
    }
    // Slow harmonics pass whole, at any speed and delay.
    CHECK(std::abs(loop_response(alpha, 187.5e-6, 10.0, 60.0) - 1.0) < 0.05);
}

TEST_CASE("the loop's response is what a simulated loop logs beyond what its currents carry", "[pmsm][current_loop]") {
    // The loop of the formula, integrated in time instead of solved: a machine of one inductance in
    // the rotor frame (L di/dt + j omega L i = applied voltage less the law's voltage w), a
    // proportional controller alpha L on the current error with the feed-forward j omega L i on the
    // current, its output applied after the delay. The steady-state model predicts a row's logged
    // voltage from the row's own current, j omega L i, plus the law's value: what the logged reference
    // holds beyond j omega L i is G w.
    using namespace std::complex_literals;
    const double alpha = 2.0 * std::numbers::pi * 400.0, delay = 187.5e-6, inductance = 7.5e-3, dt = 1.5625e-7;
    const auto delay_steps = static_cast<std::size_t>(std::lround(delay / dt));
    for (const auto [omega, omega_h] : {std::pair{628.3, 3770.0}, std::pair{628.3, -3770.0}, std::pair{-235.6, 1413.7}, std::pair{47.1, -282.7}}) {
        std::vector<std::complex<double>> sent(delay_steps, 0.0);  // the controller's outputs in flight
        std::complex<double> current = 0.0, projection = 0.0;
        const double settle = 0.05, span = 2.0 * std::numbers::pi / std::abs(omega_h) * 20.0;
        std::size_t at = 0;
        for (double t = 0.0; t < settle + span; t += dt) {
            const std::complex<double> law = std::exp(1i * omega_h * t);
            const std::complex<double> logged = -alpha * inductance * current + 1i * omega * inductance * current;
            const std::complex<double> applied = sent[at];
            sent[at] = logged;
            at = (at + 1) % delay_steps;
            if (t >= settle) projection += (logged - 1i * omega * inductance * current) * std::conj(law) * dt;
            current += dt * (applied - law - 1i * omega * inductance * current) / inductance;
        }
        // The law's voltage w is what the applied voltage loses; the loop makes up G w of it.
        const std::complex<double> simulated = projection / span;
        const std::complex<double> formula = loop_response(alpha, delay, omega, omega_h);
        INFO("omega " << omega << ", omega_h " << omega_h << ": simulated " << simulated << ", formula " << formula);
        CHECK(std::abs(simulated - formula) < 0.01 * std::abs(formula) + 0.005);
    }
}

TEST_CASE("a stated current loop takes up the dead time's harmonics the loop leaves in the current", "[pmsm][current_loop]") {
    // The 5 kW machine at its study's clear dead time (1.5 us at 8 kHz and 560 V, V_dt = 6.72 V), no
    // noise: at 2000 r/min its 6th harmonic (600 Hz) lies above the 400 Hz loop, which leaves part of
    // it in the current; the steady-state law without the loop misses that in the logged voltage.
    auto drive = read_simulation_profile(profile_path("device_5kw_profile.toml"));
    drive.noise = SensorNoise{};
    drive.device->inverter.dead_time = 1.5e-6;
    Measurement data = simulate(drive).data;
    const ModelFit without = fit_model(data, parse_model_spec("base+deadtime"), FitOptions{});
    state_current_loop(data, DriveTiming{drive.control.control_period, 0.0, 0.0, drive.control.current_bandwidth});
    const ModelFit with = fit_model(data, parse_model_spec("base+deadtime"), FitOptions{});
    INFO("rms without the loop " << without.rms.total << " V, with it " << with.rms.total << " V; V_dt " << without.values[4] << " and "
                                 << with.values[4] << " V");
    CHECK(with.rms.total < 0.7 * without.rms.total);
    CHECK(with.values[4] == Approx(6.72).epsilon(0.05));
}

TEST_CASE("a current bandwidth without the control period is refused", "[pmsm][current_loop]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "d.csv";
    const auto sim = run_mhbench("simulate " + profile_path("diagnosis_profile.toml").string() + " --out " + csv.string(), dir.path() / "log");
    REQUIRE(sim.exit_code == 0);
    const auto run = run_mhbench("fit --data " + csv.string() + " --model base+deadtime --current-bandwidth 400", dir.path() / "log");
    CHECK(run.exit_code == 2);
    CHECK(run.output.find("--current-bandwidth: current bandwidth: needs the control period as well") != std::string::npos);
}

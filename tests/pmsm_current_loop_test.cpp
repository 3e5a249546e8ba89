// The drive's current loop between the machine's voltage and the logged reference
// (model/steady_state_model.hpp, loop_response): what the steady-state model passes an effect's angle
// harmonics through once a log states the loop's bandwidth, against the closed form of a first-order
// loop and against the device plant, which switches its legs under a discrete PI controller and
// knows nothing of the formula.
#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <numbers>

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

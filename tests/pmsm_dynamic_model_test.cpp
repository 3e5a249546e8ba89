// The dynamic model (model/dynamic_model.hpp, fit/dynamic_fit.hpp): its discretisation against a
// direct numerical integration of the ODE, its fit on noise-free raw logs of the averaged and the
// device plant against the simulated motor, and its refusals of logs it cannot use.
#include <cmath>
#include <algorithm>
#include <filesystem>
#include <map>
#include <numeric>
#include <string>

#include <Eigen/LU>
#include <catch2/catch.hpp>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/fit/dynamic_fit.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb::pmsm;

namespace {

// x' = a x + b over t, classic RK4 with `steps` steps.
Eigen::Vector2d integrate(const Eigen::Matrix2d& a, const Eigen::Vector2d& b, Eigen::Vector2d x, double t, int steps) {
    const double h = t / steps;
    auto f = [&](const Eigen::Vector2d& y) -> Eigen::Vector2d { return a * y + b; };
    for (int k = 0; k < steps; ++k) {
        const Eigen::Vector2d k1 = f(x), k2 = f(x + 0.5 * h * k1), k3 = f(x + 0.5 * h * k2), k4 = f(x + h * k3);
        x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
    return x;
}

// A raw log of the Table 1 servo: logged at the control rate (100 µs) with every transient, no segment
// column, no noise: steps of i_d and of the speed between the operating points.
DriveSimulation raw_servo() {
    DriveSimulation d;
    d.logging.period = d.control.control_period;
    d.logging.transients = true;
    d.logging.segment = false;
    d.segments = {
        {"a", 10.0, 0.10, 0.0, 0.02, 100},  {"b", 25.0, 0.10, -0.2, 0.02, 100}, {"c", 25.0, 0.05, 0.15, 0.02, 100},
        {"d", -15.0, -0.08, -0.1, 0.03, 100}, {"e", -30.0, -0.12, 0.2, 0.02, 100}, {"f", 5.0, 0.02, -0.25, 0.02, 100},
    };
    return d;
}

double relative_error(double value, double truth) { return std::abs(value / truth - 1.0); }

}  // namespace

TEST_CASE("The zero-order-hold step equals a fine numerical integration of the dq ODE", "[pmsm][dynamic]") {
    struct Case {
        double rs, ld, lq, omega, dt;
    };
    // The servo, an interior-magnet machine at speed, a step long against its time constant (the
    // scaling-and-squaring path), equal inductances at standstill (repeated eigenvalues).
    for (const Case c : {Case{46.0, 0.02025, 0.02025, 30.0, 100e-6}, Case{0.05, 1.2e-3, 2.9e-3, 2000.0, 400e-6},
                         Case{46.0, 0.01, 0.03, 500.0, 5e-3}, Case{2.0, 0.01, 0.01, 0.0, 1e-3}}) {
        const Eigen::Matrix2d l = Eigen::Vector2d(c.ld, c.lq).asDiagonal();
        const ZeroOrderHoldStep step = zero_order_hold_step(c.rs, l, c.omega, c.dt);
        Eigen::Matrix2d j;
        j << 0.0, -1.0, 1.0, 0.0;
        const Eigen::Matrix2d a = -l.inverse() * (c.rs * Eigen::Matrix2d::Identity() + c.omega * j * l);
        const Eigen::Vector2d i0{0.3, -0.2}, u{5.0, -12.0};
        const Eigen::Vector2d direct = integrate(a, l.inverse() * u, i0, c.dt, 20000);
        const Eigen::Vector2d discrete = step.phi * i0 + step.gamma * u;
        INFO("rs " << c.rs << " omega " << c.omega << " dt " << c.dt);
        CHECK((discrete - direct).norm() <= 1e-10 * (1.0 + direct.norm()));
        // The integral part alone, from rest with no input but a constant drive.
        const ExponentialPair e = exponential_pair(a * c.dt);
        CHECK((e.exp * i0 - integrate(a, Eigen::Vector2d::Zero(), i0, c.dt, 20000)).norm() <= 1e-10);
    }
}

TEST_CASE("The dynamic fit of base recovers the motor from a noise-free raw log where the steady fit cannot", "[pmsm][dynamic]") {
    const auto sim = simulate(raw_servo());
    const Measurement& data = sim.data;
    const MotorParameters truth;
    const auto dynamic = fit_dynamic_model(data, parse_model_spec("base"));
    INFO(dynamic_fit_text(dynamic, data));
    CHECK(relative_error(dynamic.values[0], truth.rs) < 1e-3);
    CHECK(relative_error(dynamic.values[1], truth.ld) < 1e-3);
    CHECK(relative_error(dynamic.values[2], truth.lq) < 1e-3);
    CHECK(relative_error(dynamic.values[3], truth.psi_f) < 1e-3);
    // The steady model on the same rows takes the transients' L di/dt for error.
    FitOptions options;
    options.intervals = false;
    const auto steady = fit_model(data, parse_model_spec("base"), options);
    const double steady_worst = std::max({relative_error(steady.values[1], truth.ld), relative_error(steady.values[2], truth.lq)});
    INFO("steady Ld " << steady.values[1] << " Lq " << steady.values[2]);
    CHECK(steady_worst > 0.05);
}

TEST_CASE("The dynamic model with delay recovers the inductances and the delay of the averaged plant", "[pmsm][dynamic]") {
    auto drive = raw_servo();
    drive.effects.push_back(make_effect("delay", {{"tau", 150e-6}}));
    const auto sim = simulate(drive);
    const MotorParameters truth;
    const auto fit = fit_dynamic_model(sim.data, parse_model_spec("base+delay"));
    INFO(dynamic_fit_text(fit, sim.data));
    CHECK(relative_error(fit.values[1], truth.ld) < 0.005);
    CHECK(relative_error(fit.values[2], truth.lq) < 0.005);
    CHECK(relative_error(fit.values[4], 150e-6) < 0.01);
}

TEST_CASE("The dynamic model with delay recovers the inductances of the device plant that does not compensate its delay",
          "[pmsm][dynamic]") {
    DeviceSettings device;
    device.inverter.delay_compensation = false;
    const auto sim = simulate(with_device(raw_servo(), device, 1));
    const MotorParameters truth;
    const auto fit = fit_dynamic_model(sim.data, parse_model_spec("base+delay"));
    INFO(dynamic_fit_text(fit, sim.data));
    // Measured: L_d +0.19 %, L_q +1.75 % (issue 21 asks 2 %); the device leaves 0.2-0.3 mA of prediction
    // error that the averaged plant does not (docs/pmsm.md, "The dynamic model", what it does not do).
    CHECK(relative_error(fit.values[1], truth.ld) < 0.02);
    CHECK(relative_error(fit.values[2], truth.lq) < 0.02);
    // The device loads the duty cycles computed at a sample at the next control period: its command
    // reaches the machine one period late. (Its steady-state rotation is 1.5 omega T_s, the half period
    // more being the stationary-frame hold, which at the servo's omega T_s < 0.01 the fit cannot see;
    // docs/pmsm.md, "The dynamic model".)
    CHECK(std::abs(fit.values[4] - 100e-6) < 2e-6);
}

TEST_CASE("The dynamic model refuses a time column it cannot use, naming the row", "[pmsm][dynamic]") {
    auto data = simulate(raw_servo()).data;
    data.source = "raw.csv";
    const auto spec = parse_model_spec("base");
    SECTION("not increasing") {
        (*data.t)[40] = (*data.t)[39];
        REQUIRE_THROWS_AS(fit_dynamic_model(data, spec), mhb::InputError);
        try {
            fit_dynamic_model(data, spec);
        } catch (const mhb::InputError& e) {
            CHECK(std::string(e.what()).find("raw.csv: t: data row 41") != std::string::npos);
            CHECK(std::string(e.what()).find("does not increase") != std::string::npos);
        }
        CHECK(choose_model_kind(data, spec).kind == ModelKind::Steady);
    }
    SECTION("a gap") {
        for (Eigen::Index k = 100; k < data.size(); ++k) (*data.t)[k] += 0.01;
        try {
            fit_dynamic_model(data, spec);
            FAIL("a gap was accepted");
        } catch (const mhb::InputError& e) {
            CHECK(std::string(e.what()).find("data row 101: a gap of") != std::string::npos);
        }
        const auto choice = choose_model_kind(data, spec);
        CHECK(choice.kind == ModelKind::Steady);
        CHECK(choice.reason.find("gap") != std::string::npos);
    }
    SECTION("sampled too slowly") {
        auto slow = raw_servo();
        slow.logging.period = 4e-4;  // L/R = 0.44 ms: about one step
        auto slow_data = simulate(slow).data;
        try {
            fit_dynamic_model(slow_data, spec);
            FAIL("slow sampling was accepted");
        } catch (const mhb::InputError& e) {
            CHECK(std::string(e.what()).find("too slow for the dynamic model") != std::string::npos);
        }
        CHECK(choose_model_kind(slow_data, spec).kind == ModelKind::Steady);
    }
    SECTION("no time column") {
        data.t.reset();
        CHECK_THROWS_WITH(fit_dynamic_model(data, spec), Catch::Contains("needs the time column t"));
    }
    SECTION("too few rows") {
        std::vector<Eigen::Index> first_rows(15);
        std::iota(first_rows.begin(), first_rows.end(), Eigen::Index{0});
        const Measurement few = select_rows(data, first_rows);
        CHECK_THROWS_WITH(fit_dynamic_model(few, parse_model_spec("base+delay")), Catch::Contains("the dynamic model needs at least 20"));
    }
    SECTION("an effect the dynamic model does not have") {
        CHECK_THROWS_WITH(fit_dynamic_model(data, parse_model_spec("base+saturation")), Catch::Contains("--model-kind steady"));
    }
    SECTION("auto takes the dynamic model on the raw log") {
        const auto choice = choose_model_kind(data, spec);
        INFO(choice.reason);
        CHECK(choice.kind == ModelKind::Dynamic);
    }
}

TEST_CASE("fit --model-kind: dynamic, auto, and exit 2 on a log it cannot use", "[pmsm][dynamic][cli]") {
    const mhb::testing::TemporaryDirectory dir;
    auto data = simulate(raw_servo()).data;
    const auto raw = dir.path() / "raw.csv";
    write_measurement(raw, data);
    auto run = mhb::testing::run_mhbench("fit --data " + raw.string() + " --model-kind auto", dir.path() / "cli.log");
    INFO(run.output);
    CHECK(run.exit_code == 0);
    CHECK(run.output.find("model kind: dynamic:") != std::string::npos);
    CHECK(run.output.find("(dynamic)") != std::string::npos);

    (*data.t)[7] = (*data.t)[5];
    const auto bad = dir.path() / "bad.csv";
    write_measurement(bad, data);
    run = mhb::testing::run_mhbench("fit --data " + bad.string() + " --model-kind dynamic", dir.path() / "cli.log");
    CHECK(run.exit_code == 2);
    CHECK(run.output.find("bad.csv: t: data row 8") != std::string::npos);
    // A raw log with its segment column, less --settle after each segment start: gaps whose rows are not the file's.
    auto labelled = simulate(raw_servo()).data;
    labelled.segment_labels = {"a", "b"};
    labelled.segment = Eigen::VectorXi::Zero(labelled.size());
    labelled.segment.tail(labelled.size() / 2).setOnes();
    const auto with_segments = dir.path() / "segments.csv";
    write_measurement(with_segments, labelled);
    run = mhb::testing::run_mhbench("fit --data " + with_segments.string() + " --model-kind dynamic --settle 0.01", dir.path() / "cli.log");
    CHECK(run.exit_code == 2);
    CHECK(run.output.find("--settle: the dynamic model uses every row") != std::string::npos);
    run = mhb::testing::run_mhbench("fit --data " + bad.string() + " --model-kind auto", dir.path() / "cli.log");
    CHECK(run.exit_code == 0);
    CHECK(run.output.find("model kind: steady: data row 8") != std::string::npos);
}




// rs_thermal is not here: on the averaged plant it leaves 1-4 mA of prediction error at some segment
// changes, not traced (docs/pmsm.md, "The dynamic model").
TEST_CASE("The dynamic model takes each effect's term from the steady-state model", "[pmsm][dynamic]") {
    struct Case {
        std::string effect;
        std::map<std::string, mhb::ParameterValue> values;
        std::string parameter;
        double truth, tolerance;  // relative
    };
    for (const Case& c : {Case{"voltage_offset", {{"u_d", 0.05}, {"u_q", -0.03}}, "voltage_offset.u_d", 0.05, 0.01},
                          Case{"deadtime", {{"voltage", 0.3}, {"current_band", 0.02}}, "deadtime.voltage", 0.3, 0.01},
                          Case{"current_offset", {{"offset_a", 0.004}, {"offset_b", -0.002}}, "current_offset.offset_a", 0.004, 0.01},
                          Case{"flux_harmonic", {{"h5", 0.02}, {"phi5", 0.3}, {"h7", 0.01}, {"phi7", -0.5}}, "flux_harmonic.h5", 0.02, 0.01}}) {
        auto drive = raw_servo();
        drive.effects.push_back(make_effect(c.effect, c.values));
        const auto sim = simulate(drive);
        const auto fit = fit_dynamic_model(sim.data, parse_model_spec("base+" + c.effect));
        INFO(dynamic_fit_text(fit, sim.data));
        const MotorParameters truth;
        // Measured: within 0.1 %, dead time L_d +0.5 % (its voltage held at its value at the step's first
        // row, where it switches with the current's sign within the step).
        CHECK(relative_error(fit.values[1], truth.ld) < 0.01);
        CHECK(relative_error(fit.values[2], truth.lq) < 0.01);
        const auto j = std::find(fit.names.begin(), fit.names.end(), c.parameter) - fit.names.begin();
        CHECK(relative_error(fit.values[j], c.truth) < c.tolerance);
    }
}


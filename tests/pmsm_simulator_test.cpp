#include <catch2/catch.hpp>

#include <map>

#include "problems/pmsm/machine/flux_models.hpp"
#include "tests/pmsm_fixture.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

std::vector<std::unique_ptr<Effect>> effects_of(const std::string& name, const std::map<std::string, ParameterValue>& values) {
    std::vector<std::unique_ptr<Effect>> list;
    if (!name.empty()) list.push_back(make_effect(name, values));
    return list;
}

// Mean of a column over the rows of one segment.
double segment_mean(const Eigen::VectorXd& column, const SegmentRows& rows) {
    return column.segment(rows.first_row, rows.rows).mean();
}

}  // namespace

TEST_CASE("the ideal noise-free drive satisfies the steady-state model to rounding", "[pmsm][simulator]") {
    const auto drive = quiet_drive(seed_motor_points());
    const auto result = simulate(drive);
    REQUIRE(result.data.size() == 5 * 60);
    SteadyStateModel model(result.data, {});
    const Eigen::VectorXd r = model_residual(model, model.parameters_of(drive.motor));
    // The largest logged voltage is about 9 V; the residual is transients decayed to rounding.
    CHECK(r.cwiseAbs().maxCoeff() < 1e-8);
}

TEST_CASE("the logged shaft angle is the electrical one over the pole pairs, up to whole electrical turns", "[pmsm][simulator]") {
    for (const bool device : {false, true}) {
        INFO((device ? "device" : "averaged") << " plant");
        DriveSimulation drive = quiet_drive({{"fwd", 20.0, 0.1, 0.0, 0.3, 200}, {"rev", -20.0, -0.1, -0.1, 0.3, 200}});
        if (device) drive.device = DeviceSettings{};
        drive.logging.shaft_angle = true;
        const auto result = simulate(drive);
        REQUIRE(result.data.theta_m);
        for (Eigen::Index k = 0; k < result.data.size(); ++k) {
            const double theta_m = (*result.data.theta_m)[k];
            CHECK(std::abs(theta_m) <= std::numbers::pi);
            CHECK(std::abs(wrap_angle(drive.motor.pole_pairs * theta_m - (*result.data.theta_e)[k])) < 1e-9);
        }
        // Within each segment the shaft turns as its speed says: 20 r/min one way, then the other.
        for (std::size_t s = 0; s < result.segments.size(); ++s) {
            const auto& rows = result.segments[s];
            double travel = 0.0;
            for (Eigen::Index k = rows.first_row + 1; k < rows.first_row + rows.rows; ++k)
                travel += wrap_angle((*result.data.theta_m)[k] - (*result.data.theta_m)[k - 1]);
            const double expected = drive.segments[s].speed_rpm * std::numbers::pi / 30.0 * static_cast<double>(rows.rows - 1) * drive.logging.period;
            CHECK(travel == Approx(expected).epsilon(0.01));
        }
    }
}

TEST_CASE("steady state matches the analytic dq equations and the torque balance", "[pmsm][simulator]") {
    // A salient motor with friction, so the reluctance torque and the friction both matter.
    auto drive = quiet_drive({{"fwd", 12.0, 0.08, -0.15, 1.0, 40}, {"rev", -8.0, -0.05, -0.05, 1.0, 40}});
    drive.motor.ld = 0.015;
    drive.motor.lq = 0.025;
    drive.mechanics.viscous_friction = 0.01;
    const auto result = simulate(drive);
    const auto& m = drive.motor;
    for (std::size_t s = 0; s < drive.segments.size(); ++s) {
        const auto& seg = drive.segments[s];
        const auto& rows = result.segments[s];
        const double omega_m = seg.speed_rpm * 2.0 * std::numbers::pi / 60.0;
        const double omega = m.pole_pairs * omega_m;
        // Torque balance fixes i_q: 1.5 p (psi_f + (Ld - Lq) i_d) i_q = T_L + B omega_m.
        const double i_q = (seg.load_torque + drive.mechanics.viscous_friction * omega_m) /
                           (1.5 * m.pole_pairs * (m.psi_f + (m.ld - m.lq) * seg.i_d));
        const double u_d = m.rs * seg.i_d - omega * m.lq * i_q;
        const double u_q = m.rs * i_q + omega * m.ld * seg.i_d + omega * m.psi_f;
        CHECK(segment_mean(result.data.omega_e, rows) == Approx(omega).epsilon(1e-9));
        CHECK(segment_mean(result.data.i_d, rows) == Approx(seg.i_d).epsilon(1e-9));
        CHECK(segment_mean(result.data.i_q, rows) == Approx(i_q).epsilon(1e-9));
        CHECK(segment_mean(result.data.u_d, rows) == Approx(u_d).epsilon(1e-9));
        CHECK(segment_mean(result.data.u_q, rows) == Approx(u_q).epsilon(1e-9));
        for (Eigen::Index k = rows.first_row; k < rows.first_row + rows.rows; ++k) {
            const double torque =
                1.5 * m.pole_pairs * (m.psi_f * result.data.i_q[k] + (m.ld - m.lq) * result.data.i_d[k] * result.data.i_q[k]);
            CHECK(torque == Approx(seg.load_torque + drive.mechanics.viscous_friction * omega_m).epsilon(1e-9));
        }
        // The angle advances by omega per logging period.
        const auto& theta = *result.data.theta_e;
        const double step = wrap_angle(theta[rows.first_row + 1] - theta[rows.first_row]);
        CHECK(step == Approx(omega * drive.logging.period).epsilon(1e-9));
    }
    CHECK(result.data.segment_labels == std::vector<std::string>{"fwd", "rev"});
}

TEST_CASE("each effect's plant side is what its model side predicts", "[pmsm][simulator][effects]") {
    struct Case {
        std::string name;
        std::map<std::string, ParameterValue> values;
        double exact;  // rms residual the model with the effect must reach (V); 0: use `ratio`
        double ratio;  // else: how much smaller than the base model's residual it must be
    };
    // Exact where the effect leaves the operating point static; where it makes the currents or the
    // speed ripple (dead-time steps, sensor offsets, magnet harmonics) the L di/dt the steady-state
    // model leaves out bounds how closely it can follow.
    const std::vector<Case> cases{
        {"delay", {{"tau", 1.5e-4}}, 1e-8, 0},
        {"encoder_offset", {{"offset", 0.03}}, 1e-8, 0},
        {"rs_thermal", {}, 1e-8, 0},
        {"psi_thermal", {}, 1e-8, 0},
        {"voltage_offset", {{"u_d", 0.01}, {"u_q", -0.02}}, 1e-8, 0},
        {"saturation", {{"q_self", 0.08}, {"q_knee", 0.5}, {"cross", 0.05}, {"cross_exponent", 1.0}, {"d_even", 0.02}}, 1e-8, 0},
        {"deadtime", {{"voltage", 0.28}}, 0, 30},
        {"deadtime", {{"voltage", 0.28}, {"current_band", 0.01}}, 0, 100},
        {"current_offset", {{"offset_a", 0.001}, {"offset_b", -0.002}}, 0, 50},
        {"flux_harmonic", {{"h5", 0.01}, {"phi5", 0.5}, {"h7", 0.005}, {"phi7", -1.0}}, 0, 200},
    };
    for (const auto& c : cases) {
        INFO("effect " << c.name);
        auto drive = quiet_drive(seed_motor_points());
        drive.control.current_limit = 0.3;  // keeps the saturating plant's flux map monotone
        drive.temp_winding.points = {{0.0, 75.0}};
        drive.temp_magnet.points = {{0.0, 60.0}};
        if (c.name == "flux_harmonic") {
            // With current, the harmonics' torque ripple makes the speed loop move i_q and the model
            // would see L di/dt; at zero current only the current loop's imperfect rejection of the
            // ripple EMF remains, L Omega^2 / (R alpha_c) of it (Omega = 6 omega), which a faster loop shrinks.
            drive.segments = {{"a", 10.0, 0.0, 0.0, 0.8, 60}, {"b", -16.7, 0.0, 0.0, 0.8, 60}};
            drive.control.control_period = 25e-6;
            drive.control.integration_step = 2.5e-6;
            drive.control.current_bandwidth = 2000.0;
        }
        drive.effects = effects_of(c.name, c.values);
        const auto result = simulate(drive);
        SteadyStateModel base(result.data, {});
        SteadyStateModel full(result.data, effects_of(c.name, c.values));
        const double base_rms = rms(model_residual(base, base.parameters_of(drive.motor)));
        Eigen::VectorXd truth = full.parameters_of(drive.motor);
        if (c.name == "saturation") {
            // The plant states the law per unit of its current limit and magnet flux, the model per
            // unit of the log's: the same law in the model's units.
            const auto scale = operating_scale_of(result.data);
            const auto law = CoenergySaturation::from(truth.data() + 4, drive.control.current_limit, drive.motor.psi_f).rescaled(scale.current, scale.flux);
            const auto values = law.values();
            for (int k = 0; k < CoenergySaturation::count; ++k) truth[4 + k] = values[static_cast<std::size_t>(k)];
        }
        const double full_rms = rms(model_residual(full, truth));
        INFO("base model rms " << base_rms << " V, with the effect " << full_rms << " V");
        CHECK(base_rms > 1e-3);
        if (c.exact > 0) CHECK(full_rms < c.exact);
        else CHECK(full_rms * c.ratio < base_rms);
    }
}

TEST_CASE("thermal effects follow a temperature ramp through the record", "[pmsm][simulator][effects]") {
    for (const std::string name : {"rs_thermal", "psi_thermal"}) {
        INFO("effect " << name);
        auto drive = quiet_drive(seed_motor_points());
        drive.temp_winding.points = {{0.0, 20.0}, {3.0, 60.0}};
        drive.temp_magnet.points = {{0.0, 20.0}, {3.0, 50.0}};
        drive.effects = effects_of(name, {});
        const auto result = simulate(drive);
        CHECK((*result.data.temp_winding)[0] > 20.0);
        CHECK((*result.data.temp_winding)[result.data.size() - 1] > (*result.data.temp_winding)[0] + 10.0);
        SteadyStateModel base(result.data, {});
        SteadyStateModel full(result.data, effects_of(name, {}));
        const double base_rms = rms(model_residual(base, base.parameters_of(drive.motor)));
        const double full_rms = rms(model_residual(full, full.parameters_of(drive.motor)));
        // What remains is the drift's own rate term (d psi_f/dt on u_d, the current loop's lag behind R(t)).
        CHECK(full_rms * 25 < base_rms);
    }
}

TEST_CASE("effect residual signatures match reference/pmsm.md", "[pmsm][simulator][effects]") {
    // One steady operating point of the Table 1 motor; the base model at the true parameters leaves
    // exactly what the effect adds.
    const Segment point{"p", 10.0, 0.1, 0.0, 0.8, 500};
    const MotorParameters motor;
    const double omega = electrical_speed(motor, point.speed_rpm);
    auto residual_with = [&](const std::string& name, const std::map<std::string, ParameterValue>& values,
                             DriveSimulation drive) {
        drive.effects = effects_of(name, values);
        const auto result = simulate(drive);
        SteadyStateModel base(result.data, {});
        return std::pair{model_residual(base, base.parameters_of(drive.motor)), result.data};
    };
    const Eigen::Index n = point.samples;

    SECTION("encoder offset: Delta u_d = omega psi_f sin(delta)") {
        const double delta = 0.03;
        const auto [r, data] = residual_with("encoder_offset", {{"offset", delta}}, quiet_drive({point}));
        CHECK(r.head(n).mean() == Approx(omega * motor.psi_f * std::sin(delta)).epsilon(0.01));
        CHECK(std::abs(r.tail(n).mean()) < 0.02 * omega * motor.psi_f * delta);
    }
    SECTION("delay: Delta u_d ~ -omega tau u_q, Delta u_q ~ omega tau u_d") {
        const double tau = 1.5e-4;
        const auto [r, data] = residual_with("delay", {{"tau", tau}}, quiet_drive({point}));
        CHECK(r.head(n).mean() == Approx(-omega * tau * data.u_q.mean()).epsilon(0.01));
        CHECK(std::abs(r.tail(n).mean()) < 0.01 * omega * tau * data.u_q.mean());
    }
    SECTION("winding temperature: Delta u = Delta R i") {
        auto drive = quiet_drive({point});
        drive.temp_winding.points = {{0.0, 70.0}};
        const auto [r, data] = residual_with("rs_thermal", {}, std::move(drive));
        const double delta_r = motor.rs * 0.00393 * 50.0;
        CHECK(r.tail(n).mean() == Approx(delta_r * data.i_q.mean()).epsilon(1e-6));
        CHECK(std::abs(r.head(n).mean()) < 1e-6 * delta_r * data.i_q.mean());
    }
    SECTION("magnet temperature: omega Delta psi_f on u_q only") {
        auto drive = quiet_drive({point});
        drive.temp_magnet.points = {{0.0, 70.0}};
        const auto [r, data] = residual_with("psi_thermal", {{"alpha", -0.0011}}, std::move(drive));
        CHECK(r.tail(n).mean() == Approx(omega * motor.psi_f * -0.0011 * 50.0).epsilon(1e-6));
        CHECK(r.head(n).cwiseAbs().maxCoeff() < 1e-9);
    }
    SECTION("voltage offset: a constant residual") {
        const auto [r, data] = residual_with("voltage_offset", {{"u_d", 0.01}, {"u_q", -0.004}}, quiet_drive({point}));
        CHECK(r.head(n).minCoeff() == Approx(0.01).epsilon(1e-6));
        CHECK(r.head(n).maxCoeff() == Approx(0.01).epsilon(1e-6));
        CHECK(r.tail(n).mean() == Approx(-0.004).epsilon(1e-6));
    }
    SECTION("dead time: (4/pi) V_dt along the current, averaged over whole electrical periods") {
        // 500 samples of 0.4 ms at 2.67 Hz are 0.53 periods; average over exactly two periods instead.
        Segment two_periods = point;
        two_periods.samples = static_cast<std::int64_t>(std::llround(2.0 * 2.0 * std::numbers::pi / omega / 0.4e-3));
        const auto [r, data] = residual_with("deadtime", {{"voltage", 0.28}}, quiet_drive({two_periods}));
        const Eigen::Index m = data.size();
        // i_d = 0, so the fundamental is all on q.
        CHECK(r.tail(m).mean() == Approx(4.0 / std::numbers::pi * 0.28).epsilon(0.02));
        CHECK(std::abs(r.head(m).mean()) < 0.02 * 0.28);
        // Without the angle the model side uses that fundamental, right on average over the periods.
        Measurement no_angle = data;
        no_angle.theta_e.reset();
        SteadyStateModel mean_form(no_angle, effects_of("deadtime", {{"voltage", 0.28}}));
        const Eigen::VectorXd left = model_residual(mean_form, mean_form.parameters_of(motor));
        CHECK(std::abs(left.tail(m).mean()) < 0.02 * 0.28);
        CHECK(std::abs(left.head(m).mean()) < 0.02 * 0.28);
    }
}

TEST_CASE("sensor noise is seeded and the low-pass filter smooths it", "[pmsm][simulator]") {
    auto drive = quiet_drive({{"p", 10.0, 0.1, -0.1, 0.6, 400}});
    drive.noise.current = 1e-3;
    drive.noise.speed = 0.02;
    drive.noise.voltage = 2e-3;
    drive.seed = 11;
    const auto a = simulate(drive);
    const auto b = simulate(drive);
    CHECK(a.data.u_q == b.data.u_q);
    drive.seed = 12;
    const auto c = simulate(drive);
    CHECK(a.data.u_q != c.data.u_q);

    auto sd = [](const Eigen::VectorXd& v) { return std::sqrt((v.array() - v.mean()).square().mean()); };
    // Unfiltered, the measured current carries the sensor noise: amplitude-invariant d current noise
    // from two sensors is 1 mA times sqrt(2/3 ... 2) depending on the angle; check the order.
    CHECK(sd(a.data.i_d) > 0.5e-3);
    CHECK(sd(a.data.i_d) < 2e-3);
    drive.logging.filter_cutoff = 100.0;
    const auto filtered = simulate(drive);
    CHECK(sd(filtered.data.i_d) < 0.5 * sd(c.data.i_d));
    // The filter has unit gain at DC.
    CHECK(filtered.data.i_d.mean() == Approx(-0.1).epsilon(0.01));
}

TEST_CASE("the optional position loop holds the reducer angle", "[pmsm][simulator]") {
    auto drive = quiet_drive({{"p", 10.0, 0.1, 0.0, 3.0, 100}});
    drive.control.position_gain = 5.0;
    const auto result = simulate(drive);
    SteadyStateModel model(result.data, {});
    CHECK(rms(model_residual(model, model.parameters_of(drive.motor))) < 1e-6);
    CHECK(result.data.omega_e.mean() == Approx(electrical_speed(drive.motor, 10.0)).epsilon(1e-5));
}

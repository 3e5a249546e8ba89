// The device plant against truths derived here from the physics of each device, never from the
// effect library (whose averaged terms are what this plant is meant to test).
#include <catch2/catch.hpp>

#include <complex>
#include <filesystem>
#include <numbers>

#include <Eigen/Dense>

#include "framework/input_error.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/pmsm_fixture.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

// The Table 1 drive on the device plant, every device ideal, no noise.
DriveSimulation device_drive(std::vector<Segment> segments) {
    DriveSimulation d = quiet_drive(std::move(segments));
    d.device = DeviceSettings{};
    return d;
}

// Operating points at 45 r/min both ways (several electrical periods in a 0.4 s window) and
// currents well above the PWM ripple.
std::vector<Segment> fast_points(std::int64_t samples = 1000) {
    return {{"fwd", 45.0, 0.10, -0.15, 0.6, samples}, {"rev", -45.0, -0.08, -0.25, 0.6, samples}};
}

// Logged voltage minus the base steady-state equations at the true parameters, per sample, as a
// space vector: u_d - (R i_d - w Lq i_q) + j (u_q - (R i_q + w Ld i_d + w psi_f)).
std::vector<Complex> base_residual(const Measurement& m, const MotorParameters& p, const SegmentRows& rows) {
    std::vector<Complex> r;
    for (Eigen::Index k = rows.first_row; k < rows.first_row + rows.rows; ++k) {
        const double w = m.omega_e[k], id = m.i_d[k], iq = m.i_q[k];
        r.emplace_back(m.u_d[k] - (p.rs * id - w * p.lq * iq), m.u_q[k] - (p.rs * iq + w * p.ld * id + w * p.psi_f));
    }
    return r;
}

Complex mean(const std::vector<Complex>& v) {
    Complex s;
    for (const auto& x : v) s += x;
    return s / static_cast<double>(v.size());
}

// Runs check(segment, rows, w) on every segment of a simulated drive (w: the segment's electrical
// speed reference), naming the segment in failure reports.
template <class Check>
void each_segment(const DriveSimulation& drive, const SimulationResult& result, Check check) {
    for (std::size_t s = 0; s < drive.segments.size(); ++s) {
        INFO("segment " << drive.segments[s].label);
        check(drive.segments[s], result.segments[s], electrical_speed(drive.motor, drive.segments[s].speed_rpm));
    }
}

double column_mean(const Eigen::VectorXd& c, const SegmentRows& rows) { return c.segment(rows.first_row, rows.rows).mean(); }

// Least-squares coefficients c_n of r_k = sum_n c_n exp(j n theta_k) for the given harmonic orders n
// (0 = the constant), theta the logged angle.
std::vector<Complex> harmonic_fit(const std::vector<Complex>& r, const Measurement& m, const SegmentRows& rows,
                                  const std::vector<int>& orders) {
    Eigen::MatrixXcd a(static_cast<Eigen::Index>(r.size()), static_cast<Eigen::Index>(orders.size()));
    Eigen::VectorXcd b(static_cast<Eigen::Index>(r.size()));
    for (Eigen::Index k = 0; k < a.rows(); ++k) {
        const double theta = (*m.theta_e)[rows.first_row + k];
        for (Eigen::Index n = 0; n < a.cols(); ++n) a(k, n) = std::polar(1.0, orders[static_cast<std::size_t>(n)] * theta);
        b[k] = r[static_cast<std::size_t>(k)];
    }
    const Eigen::VectorXcd c = a.colPivHouseholderQr().solve(b);
    return {c.data(), c.data() + c.size()};
}

}  // namespace

TEST_CASE("an ideal device plant at steady state satisfies the base steady-state equations", "[pmsm][device_plant]") {
    auto points = seed_motor_points(250);
    for (const auto& s : fast_points(250)) points.push_back(s);
    const auto drive = device_drive(points);
    const auto result = simulate(drive);
    each_segment(drive, result, [&](const Segment& segment, const SegmentRows& rows, double) {
        const Complex r = mean(base_residual(result.data, drive.motor, rows));
        // What remains is the PWM current ripple: the current sampled at the zero vector's centre is
        // not exactly the period's mean (measured up to ~80 µA, i.e. ~4 mV through R_s, independent of
        // the integration step, smaller at a higher carrier frequency); ω L i is 20-60 mV.
        CHECK(std::abs(r.real()) < 5e-3);
        CHECK(std::abs(r.imag()) < 5e-3);
        CHECK(column_mean(result.data.omega_e, rows) ==
              Approx(electrical_speed(drive.motor, segment.speed_rpm)).epsilon(1e-3));
        CHECK(column_mean(result.data.i_d, rows) == Approx(segment.i_d).margin(1e-4));
    });
}

TEST_CASE("dead time loses (4/pi) t_d f_pwm V_dc along the current", "[pmsm][device_plant]") {
    // Each phase's leg is high t_d shorter (current out of the leg) or longer (into it) per carrier
    // period: its mean voltage loses t_d f V_dc sign(i_x), a square wave whose fundamental is 4/pi
    // times its height; three balanced fundamentals make a space vector of the same amplitude
    // (amplitude-invariant transform), along the current. The 6th harmonic averages out over the
    // window's whole number of sixth-periods (about 29 here).
    const double t_d = 1e-6;
    auto drive = device_drive(fast_points());
    drive.device->inverter.dead_time = t_d;
    const auto result = simulate(drive);
    const double expected = 4.0 / std::numbers::pi * t_d * drive.device->inverter.pwm_frequency * drive.control.dc_voltage;
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double) {
        const auto r = base_residual(result.data, drive.motor, rows);
        // The residual's mean projection on the current's direction, and across it.
        double along = 0.0, across = 0.0;
        for (std::size_t k = 0; k < r.size(); ++k) {
            const auto row = rows.first_row + static_cast<Eigen::Index>(k);
            const Complex direction = Complex{result.data.i_d[row], result.data.i_q[row]} / std::abs(Complex{result.data.i_d[row], result.data.i_q[row]});
            const Complex local = r[k] * std::conj(direction);
            along += local.real() / static_cast<double>(r.size());
            across += local.imag() / static_cast<double>(r.size());
        }
        CHECK(along == Approx(expected).epsilon(0.05));
        CHECK(std::abs(across) < 0.05 * expected);
    });
}

TEST_CASE("an encoder offset rotates the controller's frame: u_d shifts by w psi_f delta", "[pmsm][device_plant]") {
    // Controller frame = rotor frame + delta: i_c = e^{-j delta} i, u_c = e^{-j delta} u, so with
    // L_d = L_q, u_c = R i_c + j w L i_c + j w psi_f e^{-j delta}; to first order the d axis gains
    // w psi_f delta.
    const double delta = 0.05;
    auto drive = device_drive(fast_points(250));
    drive.device->encoder.offset = delta;
    const auto result = simulate(drive);
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double w) {
        const Complex exact = Complex{0.0, w * drive.motor.psi_f} * (std::polar(1.0, -delta) - 1.0);
        const Complex r = mean(base_residual(result.data, drive.motor, rows));
        CHECK(r.real() == Approx(w * drive.motor.psi_f * delta).epsilon(0.05));
        CHECK(std::abs(r - exact) < 5e-3);  // the ideal device's own few millivolts
    });
}

TEST_CASE("encoder quantisation: the measured angle is a whole number of counts", "[pmsm][device_plant]") {
    // 16384 lines (65536 counts): one count per control period is a speed step of 15 rad/s electrical
    // with 16 pole pairs, which the controller's raw angle difference passes to its decoupling
    // (0.7 V); much coarser encoders need a speed filter the shared controller does not have.
    const std::int64_t lines = 16384;
    auto drive = device_drive({{"a", 10.0, 0.05, 0.0, 0.3, 500}});
    drive.device->encoder.lines = lines;
    const auto result = simulate(drive);
    const double count = 2.0 * std::numbers::pi / (4.0 * static_cast<double>(lines));
    for (Eigen::Index k = 0; k < result.data.size(); ++k) {
        // theta_e = p n count up to wrapping by 2 pi, itself a whole number of p counts.
        const double counts = (*result.data.theta_e)[k] / (drive.motor.pole_pairs * count);
        CHECK(std::abs(counts - std::round(counts)) < 1e-6);
    }
    CHECK(result.data.omega_e.mean() == Approx(electrical_speed(drive.motor, 10.0)).epsilon(0.01));
}

TEST_CASE("a current sensor offset makes a ripple at the electrical frequency in dq", "[pmsm][device_plant]") {
    // The loop holds the measured current at its reference, so the true current lacks the offset:
    // a constant vector -o in the stationary frame (o = (o_a, (o_a + 2 o_b)/sqrt 3)), which needs
    // only R o there (no di/dt). In dq it turns at -w: residual -R o e^{-j theta}.
    const double o_a = 2e-3, o_b = -1e-3;
    auto drive = device_drive(fast_points(1000));
    drive.device->current_sensors.offset_a = o_a;
    drive.device->current_sensors.offset_b = o_b;
    const auto result = simulate(drive);
    const Complex o{o_a, (o_a + 2.0 * o_b) / std::numbers::sqrt3};
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double) {
        const auto c = harmonic_fit(base_residual(result.data, drive.motor, rows), result.data, rows, {0, -1, 1});
        const Complex expected = -drive.motor.rs * o;
        CHECK(std::abs(c[1] - expected) < 0.05 * std::abs(expected));
        CHECK(std::abs(c[2]) < 0.05 * std::abs(expected));
    });
}

TEST_CASE("one current sensor's gain error makes a second harmonic in dq", "[pmsm][device_plant]") {
    // Sensor a reads (1 + g) i_a: the measured alpha-beta current gains g i_a v, v = 1 + j/sqrt 3,
    // and the true current lacks it. With i_a = Re(I e^{j theta}) = (I e^{j theta} + I* e^{-j theta})/2
    // (I the dq current), the missing current has a positive-sequence part at w (needing R + j w L)
    // and a negative-sequence one at -w (R - j w L); in dq the latter turns at -2w:
    // residual -g v/2 [(R + j w L) I + (R - j w L) I* e^{-2j theta}].
    const double g = 0.02;
    auto drive = device_drive(fast_points(1000));
    drive.device->current_sensors.gain_a = 1.0 + g;
    const auto result = simulate(drive);
    const Complex v{1.0, 1.0 / std::numbers::sqrt3};
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double w) {
        const Complex current{column_mean(result.data.i_d, rows), column_mean(result.data.i_q, rows)};
        const auto c = harmonic_fit(base_residual(result.data, drive.motor, rows), result.data, rows, {0, -2, -1, 1, 2});
        const Complex expected = -g * v / 2.0 * Complex{drive.motor.rs, -w * drive.motor.lq} * std::conj(current);
        CHECK(std::abs(c[1] - expected) < 0.05 * std::abs(expected));
        CHECK(std::abs(c[2]) < 0.05 * std::abs(expected));
        CHECK(std::abs(c[4]) < 0.05 * std::abs(expected));
    });
}

TEST_CASE("magnet flux harmonics 5 and 7 make a 6th harmonic in dq", "[pmsm][device_plant]") {
    // Phase x links k_h psi_f cos(h theta_x + phi_h), theta_x = theta - 2 pi x / 3. For h = 5 the three
    // phases form a negative sequence, alpha-beta k5 psi_f e^{-j(5 theta + phi5)}; for h = 7 a positive
    // one, k7 psi_f e^{j(7 theta + phi7)}. Their EMFs (d/dt, theta' = w) in dq (times e^{-j theta}):
    // -5j w k5 psi_f e^{-j(6 theta + phi5)} and 7j w k7 psi_f e^{j(6 theta + phi7)}.
    // Without current: with it, the harmonics' torque ripple would move the speed and the currents.
    const double k5 = 0.02, phi5 = 0.4, k7 = 0.01, phi7 = -1.1;
    auto drive = device_drive({{"fwd", 45.0, 0.0, 0.0, 0.6, 1000}, {"rev", -45.0, 0.0, 0.0, 0.6, 1000}});
    drive.device->rotor_flux.harmonics = {{5, k5, phi5}, {7, k7, phi7}};
    const auto result = simulate(drive);
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double w) {
        const double psi = drive.motor.psi_f;
        const auto c = harmonic_fit(base_residual(result.data, drive.motor, rows), result.data, rows, {0, -6, 6});
        const Complex minus6 = Complex{0.0, -5.0 * w * k5 * psi} * std::polar(1.0, -phi5);
        const Complex plus6 = Complex{0.0, 7.0 * w * k7 * psi} * std::polar(1.0, phi7);
        // The current loop rejects the EMF ripple imperfectly; what it lets through the base model
        // sees as L di/dt (a few % of the EMF at 500 Hz bandwidth and 6 w = 72 Hz).
        CHECK(std::abs(c[1] - minus6) < 0.1 * std::abs(minus6));
        CHECK(std::abs(c[2] - plus6) < 0.1 * std::abs(plus6));
    });
}

TEST_CASE("rotor eccentricity makes a harmonic at mechanical order 1 in dq", "[pmsm][device_plant]") {
    // psi_d links psi_f (1 + e cos x), x = theta_m + phi: on u_q its EMF w_e psi_f e cos x, on u_d its
    // change d/dt = -w_m psi_f e sin x. As a space vector in e^{+-jx}:
    // j psi_f e [(w_e + w_m) e^{jx} + (w_e - w_m) e^{-jx}] / 2. The speed loop answers the torque's
    // once-per-turn ripple with i_q, which the base model follows from the logged currents.
    const double e = 0.03, phi = 0.6;
    // 1.4 s windows: more than a turn at 45 r/min.
    auto drive = device_drive({{"fwd", 45.0, 0.10, -0.15, 0.6, 3500}, {"rev", -45.0, -0.08, 0.0, 0.6, 3500}});
    drive.device->rotor_flux.eccentricity = e;
    drive.device->rotor_flux.eccentricity_phase = phi;
    drive.logging.shaft_angle = true;
    const auto result = simulate(drive);
    REQUIRE(result.data.theta_m);
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double w) {
        const auto r = base_residual(result.data, drive.motor, rows);
        Eigen::MatrixXcd a(static_cast<Eigen::Index>(r.size()), 3);
        Eigen::VectorXcd b(a.rows());
        for (Eigen::Index k = 0; k < a.rows(); ++k) {
            const double theta_m = (*result.data.theta_m)[rows.first_row + k];
            a.row(k) << 1.0, std::polar(1.0, theta_m), std::polar(1.0, -theta_m);
            b[k] = r[static_cast<std::size_t>(k)];
        }
        const Eigen::VectorXcd c = a.colPivHouseholderQr().solve(b);
        const double w_m = w / drive.motor.pole_pairs, psi = drive.motor.psi_f;
        const Complex plus = Complex{0.0, 0.5 * psi * e * (w + w_m)} * std::polar(1.0, phi);
        const Complex minus = Complex{0.0, 0.5 * psi * e * (w - w_m)} * std::polar(1.0, -phi);
        CHECK(std::abs(c[1] - plus) < 0.05 * std::abs(plus));
        CHECK(std::abs(c[2] - minus) < 0.05 * std::abs(minus));
    });
}

TEST_CASE("without compensation the computation delay rotates the applied voltage by 1.5 w T_s", "[pmsm][device_plant]") {
    // Sampled at the start of period k, applied over period k + 1: on average 1.5 T_s later, when the
    // rotor has turned 1.5 w T_s further; the logged reference leads the machine's voltage by that.
    for (const bool compensation : {false, true}) {
        INFO("compensation " << compensation);
        auto drive = device_drive(fast_points(250));
        drive.device->inverter.delay_compensation = compensation;
        const auto result = simulate(drive);
        each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double w) {
            const auto& p = drive.motor;
            const double i_d = column_mean(result.data.i_d, rows), i_q = column_mean(result.data.i_q, rows);
            const Complex machine{p.rs * i_d - w * p.lq * i_q, p.rs * i_q + w * p.ld * i_d + w * p.psi_f};
            const Complex logged{column_mean(result.data.u_d, rows), column_mean(result.data.u_q, rows)};
            const double rotation = std::arg(logged / machine), delay = 1.5 * w * drive.control.control_period;
            if (compensation) CHECK(std::abs(rotation) < 0.1 * std::abs(delay));
            else CHECK(rotation == Approx(delay).epsilon(0.1));
        });
    }
}

TEST_CASE("the thermal network settles where the resistive network's analytic solution puts it", "[pmsm][device_plant]") {
    // Standstill with a d current: a constant copper loss P = 1.5 R_s(T_w) |i|^2 into the winding.
    // Steady state of the network (winding -R_wa- ambient, winding -R_wm- magnet -R_ma- ambient):
    // theta_w = P R_wa (R_wm + R_ma) / (R_wa + R_wm + R_ma), theta_m = theta_w R_ma / (R_wm + R_ma), and
    // with R_s(T_w) = R_20 (1 + a (T_w - 20)) the rise solves theta_w = k (1 + a (T_amb + theta_w - 20)),
    // k = 1.5 R_20 |i|^2 R_eq.
    auto drive = device_drive({{"hold", 0.0, 0.0, -0.3, 3.0, 50}});
    auto& th = drive.device->thermal;
    th.enabled = true;
    th.winding_capacity = 0.01;  // time-compressed: time constants of a few tenths of a second
    th.magnet_capacity = 0.02;
    th.winding_to_magnet = 4.0;
    th.winding_to_ambient = 6.0;
    th.magnet_to_ambient = 15.0;
    th.ambient = 25.0;
    th.initial_winding = 25.0;
    th.initial_magnet = 25.0;
    const auto result = simulate(drive);
    const auto& rows = result.segments[0];
    const Eigen::ArrayXd id = result.data.i_d.segment(rows.first_row, rows.rows).array(), iq = result.data.i_q.segment(rows.first_row, rows.rows).array();
    const double current_squared = (id.square() + iq.square()).mean();
    const double r_eq = th.winding_to_ambient * (th.winding_to_magnet + th.magnet_to_ambient) /
                        (th.winding_to_ambient + th.winding_to_magnet + th.magnet_to_ambient);
    const double a = 0.00393;
    const double k = 1.5 * drive.motor.rs * current_squared * r_eq;
    const double rise_w = k * (1.0 + a * (th.ambient - 20.0)) / (1.0 - k * a);
    const double rise_m = rise_w * th.magnet_to_ambient / (th.winding_to_magnet + th.magnet_to_ambient);
    REQUIRE(rise_w > 10.0);
    // The PWM ripple adds a little copper loss the logged (sampled) currents do not show.
    CHECK(column_mean(*result.data.temp_winding, rows) - th.ambient == Approx(rise_w).epsilon(0.01));
    CHECK(column_mean(*result.data.temp_magnet, rows) - th.ambient == Approx(rise_m).epsilon(0.01));
}

TEST_CASE("the thermal network's temperatures change the resistance and the magnet flux", "[pmsm][device_plant]") {
    // Held temperatures (network off): R_s and psi_f follow copper's and the magnet's coefficients.
    auto drive = device_drive(fast_points(250));
    drive.device->thermal.initial_winding = 70.0;
    drive.device->thermal.initial_magnet = 60.0;
    const auto result = simulate(drive);
    MotorParameters hot = drive.motor;
    hot.rs *= 1.0 + 0.00393 * 50.0;
    hot.psi_f *= 1.0 - 0.0012 * 40.0;
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double) {
        const Complex r = mean(base_residual(result.data, hot, rows));
        CHECK(std::abs(r) < 6e-3);
        CHECK(column_mean(*result.data.temp_winding, rows) == Approx(70.0));
    });
}

TEST_CASE("saturating iron: the steady state follows the magnetic co-energy law", "[pmsm][device_plant]") {
    // psi_d = psi_f + k L_d i_d, psi_q = k L_q i_q, k = (1 + (L_d i_d^2 + L_q i_q^2) / (L_q I_sat^2))^(-1/2);
    // u_d = R i_d - w psi_q, u_q = R i_q + w psi_d.
    // At a 40 kHz carrier (four per control period): the law holds for the period's mean current, and
    // the sampled current's departure from it grows as the incremental inductance falls (at 10 kHz
    // and k = 0.8 it reaches 17 mV, against 4 mV unsaturated; at 40 kHz 2.4 mV).
    const double i_sat = 0.25;
    auto drive = device_drive(fast_points(250));
    drive.device->saturation.saturation_current = i_sat;
    drive.device->inverter.pwm_frequency = 40e3;
    const auto result = simulate(drive);
    const auto& p = drive.motor;
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double w) {
        const double i_d = column_mean(result.data.i_d, rows), i_q = column_mean(result.data.i_q, rows);
        const double k = 1.0 / std::sqrt(1.0 + (p.ld * i_d * i_d + p.lq * i_q * i_q) / (p.lq * i_sat * i_sat));
        REQUIRE(k < 0.85);
        const Complex machine{p.rs * i_d - w * k * p.lq * i_q, p.rs * i_q + w * (p.psi_f + k * p.ld * i_d)};
        const Complex logged{column_mean(result.data.u_d, rows), column_mean(result.data.u_q, rows)};
        CHECK(std::abs(logged - machine) < 5e-3);
        // and the base (unsaturated) model misses by w (1 - k) L i
        CHECK(std::abs(mean(base_residual(result.data, p, rows))) > 3.0 * std::abs(logged - machine));
    });
}

TEST_CASE("equal on-resistances of transistors and diodes are a series resistance", "[pmsm][device_plant]") {
    // Whichever device of a leg conducts, the phase sees r_on in series: R_s + r_on in the
    // steady state (the reference's "never separable from R_s").
    const double r_on = 2.0;
    auto drive = device_drive(fast_points(250));
    drive.device->inverter.switch_resistance = r_on;
    drive.device->inverter.diode_resistance = r_on;
    const auto result = simulate(drive);
    MotorParameters with_switches = drive.motor;
    with_switches.rs += r_on;
    each_segment(drive, result, [&](const Segment&, const SegmentRows& rows, double) {
        CHECK(std::abs(mean(base_residual(result.data, with_switches, rows))) < 5e-3);
        CHECK(std::abs(mean(base_residual(result.data, drive.motor, rows))) > 0.1);
    });
}

TEST_CASE("a logging-channel offset shifts only the logged voltages", "[pmsm][device_plant]") {
    const auto clean = device_drive(fast_points(100));
    auto offset = device_drive(fast_points(100));
    offset.device->logging_offset = {0.02, -0.03};
    const auto a = simulate(clean), b = simulate(offset);
    CHECK(((b.data.u_d - a.data.u_d).array() - 0.02).abs().maxCoeff() < 1e-12);
    CHECK(((b.data.u_q - a.data.u_q).array() + 0.03).abs().maxCoeff() < 1e-12);
    CHECK((b.data.i_d - a.data.i_d).cwiseAbs().maxCoeff() == 0.0);
}

TEST_CASE("a device study varies settings and seeds from one profile", "[pmsm][device_plant]") {
    const auto profile = read_simulation_profile(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" /
                                                 "device_diagnosis_profile.toml");
    DeviceSettings encoder = *profile.device;
    encoder.encoder.offset = 0.02;
    const auto a = with_device(profile, encoder, 1), b = with_device(profile, encoder, 2);
    CHECK(a.device->encoder.offset == 0.02);
    CHECK(a.seed == 1);
    CHECK(a.segments.size() == profile.segments.size());
    CHECK(a.noise.current == profile.noise.current);
    CHECK(a.logging.temperatures);
    auto shorter = [](DriveSimulation d) {
        d.segments.resize(2);
        return d;
    };
    const auto ra = simulate(shorter(with_device(profile, encoder, 1)));
    const auto ra_again = simulate(shorter(with_device(profile, encoder, 1)));
    const auto rb = simulate(shorter(with_device(profile, encoder, 2)));
    CHECK(ra.data.u_d == ra_again.data.u_d);  // a seed fixes the record
    CHECK(ra.data.u_d != rb.data.u_d);        // another seed, other noise
    CHECK(b.seed == 2);
}

TEST_CASE("the device plant refuses library effects", "[pmsm][device_plant]") {
    auto drive = device_drive(fast_points(10));
    drive.effects.push_back(make_effect("delay", {}));
    CHECK_THROWS_AS(simulate(drive), std::invalid_argument);
}

const std::string device_segment = "[[segment]]\nspeed = 10.0\nsamples = 5\n";

TEST_CASE("the device plant is read from [plant] and recorded in the sidecar", "[pmsm][device_plant][profile]") {
    const auto spec = parse_simulation_profile(R"(
[plant]
model = "device"
[plant.inverter]
dead_time = 1e-6
switch_drop = 0.7
diode_drop = 0.8
delay_compensation = false
[plant.encoder]
lines = 2500
offset = 0.02
[plant.rotor_flux]
harmonics = [{ order = 5, amplitude = 0.01, phase = 0.3 }, { order = 7, amplitude = 0.005 }]
[plant.saturation]
saturation_current = 1.5
[plant.current_sensors]
offset_a = 1e-3
gain_b = 1.01
[plant.thermal]
winding_capacity = 0.04
ambient = 25.0
[plant.logging_offset]
u_d = 0.01
)" + device_segment, "d.toml", ".");
    REQUIRE(spec.device);
    const auto& d = *spec.device;
    CHECK(d.inverter.dead_time == 1e-6);
    CHECK(d.inverter.pwm_frequency == 10e3);
    CHECK_FALSE(d.inverter.delay_compensation);
    CHECK(d.encoder.lines == 2500);
    REQUIRE(d.rotor_flux.harmonics.size() == 2);
    CHECK(d.rotor_flux.harmonics[1].order == 7);
    CHECK(d.rotor_flux.harmonics[1].phase == 0.0);
    CHECK(d.saturation.saturation_current == 1.5);
    CHECK(d.current_sensors.gain_b == 1.01);
    CHECK(d.thermal.enabled);  // giving the table switches the network on
    CHECK(d.thermal.initial_winding == 25.0);  // initial temperatures default to the ambient
    CHECK(spec.logging.temperatures);
    CHECK(d.logging_offset.u_d == 0.01);

    SimulationResult result;
    result.segments.push_back({"1", 0, 5, 0.0});
    const auto j = simulation_sidecar(spec, result, "d.toml");
    CHECK(j["plant"]["model"] == "device");
    CHECK(j["plant"]["inverter"]["dead_time"] == 1e-6);
    CHECK(j["plant"]["rotor_flux"]["harmonics"][0]["phase"] == 0.3);
    CHECK(j["plant"]["thermal"]["alpha_magnet"] == -0.0012);
    CHECK(j.contains("true_parameters_note"));

    const auto averaged = parse_simulation_profile("[plant]\nmodel = \"averaged\"\n" + device_segment, "d.toml", ".");
    CHECK_FALSE(averaged.device);
    CHECK_FALSE(simulation_sidecar(averaged, result, "d.toml").contains("plant"));
}

TEST_CASE("the shipped device profile is the clean drive at the diagnosis profile's operating points", "[pmsm][device_plant][profile]") {
    const auto dir = std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm";
    const auto device = read_simulation_profile(dir / "device_diagnosis_profile.toml");
    const auto averaged = read_simulation_profile(dir / "diagnosis_profile.toml");
    REQUIRE(device.device);
    CHECK(device.effects.empty());
    CHECK(device.logging.theta);
    CHECK(device.logging.temperatures);
    REQUIRE(device.segments.size() == averaged.segments.size());
    for (std::size_t k = 0; k < device.segments.size(); ++k) {
        CHECK(device.segments[k].label == averaged.segments[k].label);
        CHECK(device.segments[k].speed_rpm == averaged.segments[k].speed_rpm);
        CHECK(device.segments[k].load_torque == averaged.segments[k].load_torque);
        CHECK(device.segments[k].i_d == averaged.segments[k].i_d);
        CHECK(device.segments[k].samples == averaged.segments[k].samples);
    }
    const DeviceSettings ideal;
    CHECK(device.device->inverter.dead_time == ideal.inverter.dead_time);
    CHECK(device.device->encoder.offset == ideal.encoder.offset);
    CHECK(device.device->rotor_flux.harmonics.empty());
    CHECK(device.device->current_sensors.gain_a == 1.0);
    CHECK_FALSE(device.device->thermal.enabled);
}

TEST_CASE("bad device settings are refused naming file, line and field", "[pmsm][device_plant][profile]") {
    struct Refusal {
        std::string what, text;
        long line;  // 0: not checked
        std::string field, says;
    };
    const std::string device = "[plant]\nmodel = \"device\"\n";
    const std::vector<Refusal> refusals{
        {"library effects with the device plant", device + "[effects.deadtime]\nvoltage = 0.3\n", 3, "effects", "averaged plant"},
        {"prescribed temperatures with the device plant", "[temperature]\nwinding = 40\n" + device, 1, "temperature", "[plant.thermal]"},
        {"unknown model", "[plant]\nmodel = \"switching\"\n", 2, "plant.model", "device"},
        {"device tables with the averaged plant", "[plant]\n[plant.inverter]\ndead_time = 1e-6\n", 0, "plant.inverter", "unknown key"},
        {"unknown device key", device + "[plant.encoder]\nline = 1000\n", 4, "plant.encoder.line", "lines"},
        {"wrong type", device + "[plant.inverter]\ndelay_compensation = 1\n", 4, "plant.inverter.delay_compensation", "true or false"},
        {"out of range", device + "[plant.current_sensors]\ngain_a = 0.0\n", 4, "plant.current_sensors.gain_a", "(0, 10]"},
        {"carrier that does not tile the control period", device + "[plant.inverter]\npwm_frequency = 15e3\n", 4,
         "plant.inverter.pwm_frequency", "whole number"},
        {"dead time of a quarter carrier", device + "[plant.inverter]\ndead_time = 30e-6\n", 4, "plant.inverter.dead_time", "quarter"},
        {"a triplen flux harmonic", device + "[plant.rotor_flux]\nharmonics = [{ order = 9, amplitude = 0.01 }]\n", 4,
         "plant.rotor_flux.harmonics[1].order", "multiple of 3"},
        {"an eccentricity beyond half the magnet flux", device + "[plant.rotor_flux]\neccentricity = 0.6\n", 4,
         "plant.rotor_flux.eccentricity", "[0, 0.5]"},
        {"an eccentricity phase beyond pi", device + "[plant.rotor_flux]\neccentricity_phase = 4.0\n", 4,
         "plant.rotor_flux.eccentricity_phase", "must lie in"},
        {"a shaft angle logged as a number", "[logging]\ntheta_m = 1\n", 2, "logging.theta_m", "true or false"},
    };
    for (const auto& r : refusals) {
        INFO(r.what);
        try {
            parse_simulation_profile(r.text + device_segment, "d.toml", ".");
            FAIL("accepted");
        } catch (const InputError& e) {
            CHECK(e.file() == "d.toml");
            if (r.line) CHECK(e.line() == r.line);
            CHECK(e.field() == r.field);
            CHECK(e.message().find(r.says) != std::string::npos);
        }
    }
}

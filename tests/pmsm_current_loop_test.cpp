// The drive's current loop between the machine's voltage and the logged reference
// (model/steady_state_model.hpp, pass_through_current_loop): what the steady-state model passes an effect's angle
// harmonics through once a log states the loop's bandwidth, against the closed form of a first-order
// loop and against the device plant, which switches its legs under a discrete PI controller and
// knows nothing of the formula.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <random>
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

namespace {

// The continuous loop's response to a harmonic of the law turning at omega_h in the rotor frame at
// speed omega, beyond what the rows' own currents carry (docs/diagnosis.md, section 8), its delay
// tau: alpha / ((alpha - j omega) e^{-j omega_h tau} + j (omega_h + omega)).
std::complex<double> continuous_response(double alpha, double tau, double omega, double omega_h) {
    using namespace std::complex_literals;
    const std::complex<double> a = alpha - 1i * omega;
    return alpha / (a * std::exp(-1i * omega_h * tau) + 1i * (omega_h + omega));
}

// The model's loop over rows at one speed, the period's map made at the first row's.
void pass_through(const CurrentLoop& loop, const std::vector<double>& speed, const std::vector<std::uint8_t>& steps, std::vector<double>& w_d,
                  std::vector<double>& w_q) {
    pass_through_current_loop(loop, loop_period(loop, speed.front()), speed.data(), steps.data(), w_d.data(), w_q.data(),
                              static_cast<Eigen::Index>(speed.size()));
}

// The model's loop on a law e^{j omega_h t} sampled every control period, `rows` rows of one run:
// the phasor of what it puts in the reference over the last half of the rows.
std::complex<double> filtered_phasor(const CurrentLoop& loop, double omega, double omega_h, Eigen::Index rows) {
    std::vector<double> speed(static_cast<std::size_t>(rows), omega), w_d(speed.size()), w_q(speed.size());
    std::vector<std::uint8_t> steps(speed.size(), 1);
    for (Eigen::Index k = 0; k < rows; ++k) {
        const auto law = std::polar(1.0, omega_h * loop.period * static_cast<double>(k));
        w_d[static_cast<std::size_t>(k)] = law.real();
        w_q[static_cast<std::size_t>(k)] = law.imag();
    }
    pass_through(loop, speed, steps, w_d, w_q);
    std::complex<double> sum = 0.0;
    for (Eigen::Index k = rows / 2; k < rows; ++k)
        sum += std::complex<double>(w_d[static_cast<std::size_t>(k)], w_q[static_cast<std::size_t>(k)]) *
               std::polar(1.0, -omega_h * loop.period * static_cast<double>(k));
    return sum / static_cast<double>(rows - rows / 2);
}

}  // namespace

TEST_CASE("the model's loop passes a constant law whole and follows a first-order low pass as its period shrinks", "[pmsm][current_loop]") {
    const double alpha = 2.0 * std::numbers::pi * 400.0;
    for (const double corner : {0.0, 67.0, 2270.0})
        CHECK(std::abs(filtered_phasor(CurrentLoop{alpha, 125e-6, corner, corner}, 628.3, 0.0, 400) - 1.0) < 1e-9);
    // An IMC-tuned PI loop without delay or speed and without resistance closes to alpha / (s +
    // alpha); with a period of 1 us the held voltage and the delay of 1.5 periods hardly differ.
    for (const double omega_h : {-5000.0, -300.0, 100.0, 2513.0, 20000.0}) {
        const std::complex<double> first_order = alpha / std::complex<double>(alpha, omega_h);
        const std::complex<double> model = filtered_phasor(CurrentLoop{alpha, 1e-6}, 0.0, omega_h, 200000);
        INFO("omega_h " << omega_h << ": model " << model << ", first order " << first_order);
        CHECK(std::abs(model - first_order) < 0.01 * std::abs(first_order) + 1e-3);
    }
}

TEST_CASE("the model's loop is what a simulated loop logs beyond what its currents carry", "[pmsm][current_loop]") {
    // The loop integrated in time in fine steps: a salient machine in the rotor frame (L_d di_d/dt =
    // v_d - R i_d + omega L_q i_q, L_q di_q/dt = v_q - R i_q - omega L_d i_d, v the applied voltage less
    // the law's voltage), a PI controller per axis (K_p = alpha L, K_i = alpha R, its integral
    // updated after each output) on the sampled current with the feed-forward of j omega L i on that
    // current, its output applied over the next control period, the law turning in time. The
    // steady-state model predicts a row's logged voltage from the row's own current, R i + j omega L i,
    // plus its law: what the logged reference holds beyond that is what the model's loop must give.
    using namespace std::complex_literals;
    const double period = 125e-6;
    const int substeps = 400;
    const double dt = period / substeps;
    struct Case {
        double alpha, resistance, ld, lq, omega, omega_h;
    };
    const double a5 = 2.0 * std::numbers::pi * 400.0, a_servo = 2.0 * std::numbers::pi * 250.0;
    for (const Case& c : {Case{a5, 0.5, 6e-3, 9e-3, 628.3, 3770.0}, Case{a5, 0.5, 6e-3, 9e-3, 628.3, -3770.0},
                          Case{a5, 0.5, 6e-3, 9e-3, -235.6, 1413.7}, Case{a5, 0.0, 7.5e-3, 7.5e-3, 47.1, -282.7},
                          Case{a_servo, 46.0, 20.25e-3, 20.25e-3, 200.0, 1200.0}, Case{a_servo, 46.0, 20.25e-3, 20.25e-3, 40.0, -240.0}}) {
        const Eigen::Index rows = 800;
        std::vector<double> speed(static_cast<std::size_t>(rows), c.omega), w_d(speed.size()), w_q(speed.size());
        std::vector<std::uint8_t> steps(speed.size(), 1);
        std::vector<std::complex<double>> logged(speed.size());
        double id = 0.0, iq = 0.0, yd = 0.0, yq = 0.0, applied_d = 0.0, applied_q = 0.0;
        for (Eigen::Index k = 0; k < rows; ++k) {
            const auto row = static_cast<std::size_t>(k);
            const std::complex<double> law = std::polar(1.0, c.omega_h * period * static_cast<double>(k));
            w_d[row] = law.real();
            w_q[row] = law.imag();
            const double output_d = -c.alpha * c.ld * id + yd - c.omega * c.lq * iq;
            const double output_q = -c.alpha * c.lq * iq + yq + c.omega * c.ld * id;
            logged[row] = {output_d - (c.resistance * id - c.omega * c.lq * iq), output_q - (c.resistance * iq + c.omega * c.ld * id)};
            yd -= c.alpha * c.resistance * period * id;
            yq -= c.alpha * c.resistance * period * iq;
            // Midpoint steps over the period: the controller's voltage is held, the law turns on.
            for (int m = 0; m < substeps; ++m) {
                const std::complex<double> w = std::polar(1.0, c.omega_h * (period * static_cast<double>(k) + dt * (m + 0.5)));
                auto slope_d = [&](double d, double q) { return (applied_d - w.real() - c.resistance * d + c.omega * c.lq * q) / c.ld; };
                auto slope_q = [&](double d, double q) { return (applied_q - w.imag() - c.resistance * q - c.omega * c.ld * d) / c.lq; };
                const double hd = id + 0.5 * dt * slope_d(id, iq), hq = iq + 0.5 * dt * slope_q(id, iq);
                id += dt * slope_d(hd, hq);
                iq += dt * slope_q(hd, hq);
            }
            applied_d = output_d;
            applied_q = output_q;
        }
        const CurrentLoop loop{c.alpha, period, c.resistance / c.ld, c.resistance / c.lq};
        pass_through(loop, speed, steps, w_d, w_q);
        // Compared once both starts have settled (the model starts at the loop's steady state, the
        // simulation at zero current).
        double worst = 0.0;
        for (std::size_t k = static_cast<std::size_t>(rows / 2); k < speed.size(); ++k)
            worst = std::max(worst, std::abs(logged[k] - std::complex<double>(w_d[k], w_q[k])));
        INFO("alpha " << c.alpha << ", R " << c.resistance << ", omega " << c.omega << ", omega_h " << c.omega_h << ": largest difference "
                      << worst << " of a law of 1");
        // The model takes the law over a period on the line between two rows: off a turning law by
        // about (omega_h T)^2 / 12, 1.8 % at 600 Hz and 8 kHz.
        const double step = std::abs(c.omega_h) * period;
        CHECK(worst < 0.1 * step * step + 0.006);
        if (c.resistance == 0.0) {
            // Without resistance, against the continuous closed form with a delay of 1.5 periods: near
            // it, not equal (a held voltage is not a delay).
            const std::complex<double> model = filtered_phasor(loop, c.omega, c.omega_h, 4000);
            const std::complex<double> closed = continuous_response(c.alpha, 1.5 * period, c.omega, c.omega_h);
            INFO("model " << model << ", closed form " << closed);
            CHECK(std::abs(model - closed) < 0.05 * std::abs(closed));
        }
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
                                 << with.values[4] << " V; Rs " << without.values[0] << " and " << with.values[0] << " Ohm");
    // Taken at each row's own current the law left 0.376 V (0.40 of it); at the current less its noise,
    // the mean state and one pass of the ripple (below), 0.514 V (0.54): the price of keeping the
    // sensors' noise out of the loop.
    CHECK(with.rms.total < 0.6 * without.rms.total);
    CHECK(with.values[4] == Approx(6.72).epsilon(0.03));
    CHECK(with.values[0] == Approx(0.5).epsilon(0.04));
}

TEST_CASE("a run of the model's loop starts again at a row that does not follow the one before", "[pmsm][current_loop]") {
    const CurrentLoop loop{2.0 * std::numbers::pi * 400.0, 125e-6, 67.0, 56.0};
    std::vector<double> speed(100, 628.3), w_d(100), w_q(100);
    for (std::size_t k = 0; k < w_d.size(); ++k) {
        w_d[k] = k < 50 ? 1.0 : -1.0;  // a step at row 50, as a phase current's sign turns
        w_q[k] = 0.5;
    }
    std::vector<std::uint8_t> steps(100, 1);
    auto joined_d = w_d, joined_q = w_q;
    pass_through(loop, speed, steps, joined_d, joined_q);
    steps[50] = 0;
    pass_through(loop, speed, steps, w_d, w_q);
    // Joined, the loop lags the step; started again, the row is the law itself.
    CHECK(std::abs(joined_d[50] - -1.0) > 0.5);
    CHECK(w_d[50] == Approx(-1.0).margin(1e-12));
    CHECK(w_q[50] == Approx(0.5).margin(1e-12));
    CHECK(w_d[49] == Approx(joined_d[49]).margin(1e-15));
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

TEST_CASE("what the model's loop adds is taken at the current less the sensors' noise", "[pmsm][current_loop]") {
    // The servo (46 Ohm, 20 mH, a 250 Hz loop) with its 1 us dead time, noise-free, and the same log
    // with its sensors' 1 mA of current noise added; a dead-time law with a band of 20 mA, wide enough
    // to follow that noise (its slope 0.28 V / 20 mA turns 1 mA into 14 mV). What the loop adds to the
    // law must not follow it: the loop's answer to the noise is delay's signature (docs/diagnosis.md,
    // section 8). Each run's mean state carries the noise of its mean, 1 mA over the square root of
    // its rows.
    auto drive = read_simulation_profile(profile_path("device_diagnosis_profile.toml"));
    drive.noise = SensorNoise{};
    drive.device->inverter.dead_time = 1e-6;
    Measurement clean = simulate(drive).data;
    state_current_loop(clean, DriveTiming{drive.control.control_period, 0.0, 0.0, drive.control.current_bandwidth});
    Measurement noisy = clean;
    std::mt19937_64 generator(11);
    std::normal_distribution<double> noise(0.0, 1e-3);
    for (Eigen::Index k = 0; k < noisy.size(); ++k) {
        noisy.i_d[k] += noise(generator);
        noisy.i_q[k] += noise(generator);
    }
    // What the loop adds: the prediction with the loop stated less the one without.
    auto loop_part = [&](const Measurement& data) {
        Measurement without = data;
        without.current_loop_bandwidth = 0.0;
        Eigen::VectorXd part(2 * data.size());
        for (const Measurement* m : {&data, static_cast<const Measurement*>(&without)}) {
            const auto model = make_model(parse_model_spec("base+deadtime"), *m);
            Eigen::VectorXd v = model->parameters_of(drive.motor);
            v[4] = 0.28;
            v[5] = 0.02;
            Eigen::VectorXd u_d(data.size()), u_q(data.size());
            model->predict_rows(v.data(), u_d.data(), u_q.data());
            Eigen::VectorXd stacked(2 * data.size());
            stacked << u_d, u_q;
            if (m == &data) part = stacked;
            else part -= stacked;
        }
        return part;
    };
    const Eigen::VectorXd at_clean = loop_part(clean), at_noisy = loop_part(noisy);
    const double size = std::sqrt(at_clean.squaredNorm() / static_cast<double>(at_clean.size()));
    const double moved = std::sqrt((at_noisy - at_clean).squaredNorm() / static_cast<double>(at_clean.size()));
    INFO("what the loop adds: " << 1e3 * size << " mV rms; moved by the noise " << 1e3 * moved << " mV rms");
    CHECK(size > 0.002);
    CHECK(moved < 0.1 * size);
}

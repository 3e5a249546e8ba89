// Noise the logged current and voltage share (problems/pmsm/diagnosis/shared_noise.hpp): a fit's bias
// from it, measured within the steady windows, against the parameters the data were made with. First
// on logs written here from the steady-state equations, whose current sensors' noise a proportional
// controller answers (a known, exact mechanism, sharing no code with the estimate); then on the device
// plant's closed current loop, the 5 kW machine's raw logs with their 25 mA of current noise.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>

#include <nlohmann/json.hpp>

#include "problems/pmsm/data/operating_points.hpp"
#include "problems/pmsm/diagnosis/shared_noise.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/model/model_spec.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/mhbench_cli.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb::pmsm;

namespace {

const Eigen::Vector4d machine{0.5, 0.006, 0.009, 0.3};  // Rs, Ld, Lq, psi_f of a 5 kW machine

// Twelve steady windows of 3000 rows, 125 us apart, at the operating points of a 5 kW drive. The
// true currents hold still; the sensors add white noise of `current_noise` (A) to what is logged,
// and the controller answers each sample's noise with -gain times it in the voltage it logs, besides
// the steady-state voltage of the true current and white voltage noise of `voltage_noise` (V).
Measurement proportional_loop(double gain, double current_noise, double voltage_noise, unsigned seed) {
    std::mt19937_64 random(seed);
    std::normal_distribution<double> normal;
    const Eigen::Index rows = 3000;
    const double dt = 125e-6;
    Measurement m;
    m.resize(12 * rows);
    m.t = Eigen::VectorXd(m.size());
    m.theta_e = Eigen::VectorXd(m.size());
    m.segment.resize(m.size());
    int s = 0;
    for (const double omega : {150.0, 600.0})
        for (const double i_d : {0.0, -4.0})
            for (const double i_q : {3.0, 9.0, 15.0}) {
                m.segment_labels.push_back("w" + std::to_string(s));
                for (Eigen::Index k = 0; k < rows; ++k) {
                    const Eigen::Index row = s * rows + k;
                    const double e_d = current_noise * normal(random), e_q = current_noise * normal(random);
                    m.i_d[row] = i_d + e_d;
                    m.i_q[row] = i_q + e_q;
                    m.omega_e[row] = omega;
                    m.u_d[row] = machine[0] * i_d - omega * machine[2] * i_q - gain * e_d + voltage_noise * normal(random);
                    m.u_q[row] = machine[0] * i_q + omega * (machine[1] * i_d + machine[3]) - gain * e_q + voltage_noise * normal(random);
                    (*m.t)[row] = static_cast<double>(row) * dt + s;
                    (*m.theta_e)[row] = std::remainder(omega * static_cast<double>(k) * dt, 2.0 * std::numbers::pi);
                    m.segment[row] = s;
                }
                ++s;
            }
    return m;
}

struct Corrected {
    Eigen::Vector4d before, after;  // (fitted - true) / true, without and with the correction
    SharedNoise shared;
};

Corrected fit_and_correct(const Measurement& data, const Eigen::Vector4d& truth) {
    const ModelFit fit = fit_model(data, parse_model_spec("base"), FitOptions{});
    const auto shared = shared_noise_bias(data, fit);
    REQUIRE(shared);
    return {fit.values.head<4>().cwiseQuotient(truth).array() - 1.0, (fit.values.head<4>() - shared->bias).cwiseQuotient(truth).array() - 1.0,
            *shared};
}

// The 5 kW machine's raw log of noise seed `seed`, with its true base parameters.
struct RawDrive {
    Measurement data;
    Eigen::Vector4d truth;
    double control_period = 0.0;
};
RawDrive raw_5kw_drive(unsigned seed) {
    auto drive = read_simulation_profile(mhb::pmsm::testing::profile_path("device_5kw_profile.toml"));
    drive.logging.transients = true;
    drive.logging.segment = false;
    drive.seed = seed;
    return {simulate(drive).data, {drive.motor.rs, drive.motor.ld, drive.motor.lq, drive.motor.psi_f}, drive.control.control_period};
}

}  // namespace

TEST_CASE("the bias a proportional loop's answer to the current sensors' noise puts in a fit is measured and removed", "[pmsm][shared_noise]") {
    // Rs reads low by about (gain + Rs) sigma^2 over the mean square of its regressor over both axes'
    // rows, 10.5 x 0.01 / 56.5 = 0.0019 ohm (0.37 %), and more through its correlation with the
    // inductances' columns: 0.73 %, four of the fit's standard errors.
    double before = 0.0, after = 0.0, error = 0.0;
    const int seeds = 8;
    for (int seed = 1; seed <= seeds; ++seed) {
        INFO("seed " << seed);
        const Corrected c = fit_and_correct(proportional_loop(10.0, 0.1, 0.5, static_cast<unsigned>(seed)), machine);
        CHECK(c.shared.relevant());
        CHECK(c.shared.windows == 12);
        const double standard_error = c.shared.fit_standard_error[0] / machine[0];
        CHECK(std::abs(c.after[0]) < 3.0 * standard_error);
        before += c.before[0] / seeds;
        after += c.after[0] / seeds;
        error += standard_error / seeds;
    }
    CHECK(before < -3.0 * error);             // the loop's bias is there
    CHECK(std::abs(after) < error);           // and gone after the correction, on average over the seeds
}

TEST_CASE("noise in the current that the voltage does not share leaves a bias too small to state", "[pmsm][shared_noise]") {
    // Without the loop's answer, the current's noise only attenuates each parameter by about
    // sigma^2 over its regressor's mean square (Rs: 0.0004 / 56.5, 0.0007 %; Ld, whose regressor
    // omega i_d is smallest: 0.0004 / 8, 0.005 %), a fifth of the fit's standard error at most.
    int stated = 0;
    for (int seed = 1; seed <= 8; ++seed) {
        INFO("seed " << seed);
        const Corrected c = fit_and_correct(proportional_loop(0.0, 0.02, 0.5, static_cast<unsigned>(seed)), machine);
        stated += c.shared.relevant() ? 1 : 0;
        for (int j = 0; j < 4; ++j) CHECK(std::abs(c.shared.bias[j]) < 0.3 * c.shared.fit_standard_error[j]);
    }
    CHECK(stated <= 1);
}

TEST_CASE("without an angle or a time the shared noise is not measured", "[pmsm][shared_noise]") {
    Measurement data = proportional_loop(10.0, 0.1, 0.5, 1);
    data.theta_e.reset();
    data.t.reset();
    const ModelFit fit = fit_model(data, parse_model_spec("base"), FitOptions{});
    CHECK_FALSE(shared_noise_bias(data, fit).has_value());
}

TEST_CASE("on the 5 kW machine's raw logs the closed loop's bias on Rs is removed and the intervals hold the truth", "[pmsm][shared_noise]") {
    // Controlled by the device plant's own PI current loop at 8 kHz, the logged voltage answers the
    // sensors' 25 mA of noise; Rs read about 0.3 % low, beyond its 95 % interval (detection_study_raw_5kw).
    for (const unsigned seed : {1u, 2u}) {
        INFO("seed " << seed);
        const RawDrive drive = raw_5kw_drive(seed);
        const auto points = find_operating_points(drive.data);
        const Measurement data = select_operating_points(Measurement(drive.data), points);
        const Eigen::Vector4d& truth = drive.truth;
        const ModelFit fit = fit_model(data, parse_model_spec("base"), FitOptions{});
        const auto shared = shared_noise_bias(data, fit);
        REQUIRE(shared);
        CHECK(shared->relevant());
        // The sample and hold's share (+0.16 % on Rs, sample_and_hold_test) set aside, as the study does.
        const Eigen::Vector4d held = sample_and_hold_bias(data, fit.values.head<4>(), DriveTiming{drive.control_period});
        const double before = fit.values[0] - held[0], after = before - shared->bias[0];
        CHECK_FALSE((fit.lower[0] - held[0] <= truth[0] && truth[0] <= fit.upper[0] - held[0]));
        const auto [lower, upper] = shared->corrected_interval(fit, 0, held[0]);
        CHECK((lower <= truth[0] && truth[0] <= upper));
        CHECK(std::abs(after / truth[0] - 1.0) < 0.3 * std::abs(before / truth[0] - 1.0));
    }
}

TEST_CASE("fit states the shared noise where it matters and writes it to JSON, corrected for it and the sample and hold", "[pmsm][shared_noise][cli]") {
    mhb::testing::TemporaryDirectory dir;
    const RawDrive drive = raw_5kw_drive(3);
    const auto csv = dir.path() / "raw.csv", json = dir.path() / "fit.json";
    write_measurement(csv, drive.data);
    const auto fit = mhb::testing::run_mhbench("fit --data " + csv.string() + " --model base --control-period 125e-6 --json " + json.string(), dir.path() / "log");
    INFO(fit.output);
    REQUIRE(fit.exit_code == 0);
    CHECK(fit.output.find("noise the current and the voltage share") != std::string::npos);
    CHECK(fit.output.find("corrected for it and for the sample and hold above") != std::string::npos);
    const auto shared = nlohmann::json::parse(mhb::testing::read_file(json)).at("shared_noise");
    CHECK(shared.at("relevant").get<bool>());
    CHECK(shared.at("windows").get<int>() >= 3);
    CHECK(shared.at("bias").at("Rs").get<double>() < -0.001);  // the loop reads Rs low
    const auto& rs = shared.at("corrected").at("Rs");
    CHECK(std::abs(rs.at("value").get<double>() / drive.truth[0] - 1.0) < 0.001);
    CHECK(rs.at("ci95").at(0).get<double>() <= drive.truth[0]);
    CHECK(drive.truth[0] <= rs.at("ci95").at(1).get<double>());
}

#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>

#include "framework/input_error.hpp"
#include "framework/random.hpp"
#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/machine/flux_models.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "problems/pmsm/study/detection_study.hpp"
#include "problems/pmsm/fit/linear_fit.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "tests/pmsm_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

const std::filesystem::path map_path = std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "data" / "motulator_baldor_pmsyrm_400rpm_fluxmap.csv";

// The map's rows read independently of FluxMap: (i_d, i_q) -> (psi_d, psi_q).
std::map<std::pair<double, double>, std::pair<double, double>> raw_map() {
    std::ifstream in(map_path);
    std::string line;
    std::getline(in, line);
    std::map<std::pair<double, double>, std::pair<double, double>> rows;
    while (std::getline(in, line)) {
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream s(line);
        double id, iq, pd, pq;
        s >> id >> iq >> pd >> pq;
        rows[{id + 0.0, iq + 0.0}] = {pd, pq};
    }
    return rows;
}

// The Baldor machine of the map (2 pole pairs, 0.63 Ω) on a stiff shaft, controller tuned with its
// small-signal inductances; the plant is the measured map.
DriveSimulation baldor_drive(std::vector<Segment> segments) {
    DriveSimulation d;
    d.motor = {0.63, 0.031, 0.141, 0.444, 2};
    d.mechanics = {0.015, 0.0, 1.0, 0.0};
    d.control.dc_voltage = 540.0;
    d.control.current_limit = 20.0;
    d.segments = std::move(segments);
    d.base_directory = map_path.parent_path();
    d.effects.push_back(make_effect("saturation", {{"flux_map", map_path.filename().string()}}));
    return d;
}

// Columns of a model that is linear in its parameters: the prediction for each unit vector.
Eigen::MatrixXd linear_columns(const SteadyStateModel& model) {
    const Eigen::Index n = model.data().size(), p = model.parameter_count();
    Eigen::MatrixXd phi(2 * n, p);
    ModelState s = model.make_state();
    for (Eigen::Index j = 0; j < p; ++j) {
        const Eigen::VectorXd unit = Eigen::VectorXd::Unit(p, j);
        model.predict(unit.data(), s);
        phi.col(j) << s.u_d.matrix(), s.u_q.matrix();
    }
    return phi;
}

// The log of one drive of a study in experiments/pmsm/ (`only`: design/case), simulated as the study
// simulates it with that seed.
Measurement study_drive(const std::string& file, const std::string& only, std::uint64_t seed) {
    auto spec = read_study(std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / file);
    spec.only = only;
    const auto cases = study_cases(spec);
    REQUIRE(cases.size() == 1);
    return simulate(parse_simulation_profile(case_profile(spec, cases.front(), seed), file, spec.profile.parent_path())).data;
}

// A study drive (study_drive, seed 1) and its diagnosis from the base model with the default options.
struct DiagnosedDrive {
    Measurement data;
    Diagnosis d;
};
DiagnosedDrive diagnosed_drive(const std::string& file, const std::string& only) {
    Measurement data = study_drive(file, only, 1);
    Diagnosis d = diagnose(data, parse_model_spec("base"), DiagnosisOptions{});
    return {std::move(data), std::move(d)};
}

// The recommended model's interval caveat whose reason holds `text`, or null.
const IntervalCaveat* caveat_with(const Diagnosis& d, const std::string& text) {
    const auto found = std::find_if(d.interval_caveats.begin(), d.interval_caveats.end(),
                                    [&](const IntervalCaveat& c) { return c.reason.find(text) != std::string::npos; });
    return found == d.interval_caveats.end() ? nullptr : &*found;
}

}  // namespace

TEST_CASE("the flux map reproduces its grid, interpolates bilinearly and inverts", "[pmsm][flux_map]") {
    const auto raw = raw_map();
    REQUIRE(raw.size() == 567);
    const FluxMap map = FluxMap::read(map_path, 1.0);
    CHECK(map.i_d_grid().size() == 21);
    CHECK(map.i_q_grid().size() == 27);
    for (const auto& [i, psi] : raw) {
        const Complex f = map.flux({i.first, i.second}, 1.0);
        CHECK(f.real() == psi.first);
        CHECK(f.imag() == psi.second);
    }
    CHECK(map.magnet_flux() == raw.at({0.0, 0.0}).first);
    // Inside a cell the interpolant is bilinear: its centre is the mean of the four corners.
    const Complex centre = map.flux({-3.0, 5.0}, 1.0);
    const auto& a = raw.at({-4.0, 4.0});
    const auto& b = raw.at({-2.0, 4.0});
    const auto& c = raw.at({-4.0, 6.0});
    const auto& d = raw.at({-2.0, 6.0});
    CHECK(centre.real() == Approx((a.first + b.first + c.first + d.first) / 4).epsilon(1e-14));
    CHECK(centre.imag() == Approx((a.second + b.second + c.second + d.second) / 4).epsilon(1e-14));
    // A cooler or hotter magnet scales the map's own magnet flux.
    CHECK(map.flux({0.0, 0.0}, 0.9).real() == Approx(0.9 * map.magnet_flux()).epsilon(1e-14));
    // Beyond the grid the edge cell extends linearly.
    const Complex edge = map.flux({20.0, 0.0}, 1.0), beyond = map.flux({22.0, 0.0}, 1.0);
    const Complex inner = map.flux({18.0, 0.0}, 1.0);
    CHECK((beyond - edge).real() == Approx((edge - inner).real()).epsilon(1e-12));
    // The current for a flux linkage, from a poor starting guess.
    Rng rng(3);
    for (int k = 0; k < 200; ++k) {
        const Complex i{rng.uniform(-19.0, 19.0), rng.uniform(-25.0, 25.0)};
        const Complex back = map.current(map.flux(i, 1.0), 1.0, {0.0, 0.0});
        CHECK(std::abs(back - i) < 1e-9);
    }
}

TEST_CASE("a malformed flux map is refused with its line", "[pmsm][flux_map]") {
    const mhb::testing::TemporaryDirectory dir;
    const auto path = dir.path() / "bad_fluxmap.csv";
    auto refusal = [&](const std::string& text) {
        std::ofstream(path) << text;
        try {
            FluxMap::read(path, 1.0);
        } catch (const InputError& e) {
            return e;
        }
        FAIL("accepted a malformed flux map");
        throw std::logic_error("unreachable");
    };
    auto e = refusal("i_d_A,i_q_A,psi_d_Vs,psi_q_Vs\n0,0,0.4,0\n0,1,0.4,x\n");
    CHECK(e.line() == 3);
    CHECK(e.field() == "psi_q_Vs");
    e = refusal("i_d_A,i_q_A,psi_d_Vs\n0,0,0.4\n");
    CHECK(e.field() == "psi_q_Vs");
    e = refusal("i_d_A,i_q_A,psi_d_Vs,psi_q_Vs\n0,0,0.4,0\n0,1,0.4,0.1\n1,0,0.5,0\n");
    CHECK(e.message().find("lacks the point (i_d, i_q) = (1, 1) A") != std::string::npos);
    e = refusal("i_d_A,i_q_A,psi_d_Vs,psi_q_Vs\n0,0,0.4,0\n0,0,0.4,0.1\n");
    CHECK(e.line() == 3);
    // One current value on an axis: nothing to interpolate between.
    e = refusal("i_d_A,i_q_A,psi_d_Vs,psi_q_Vs\n0,0,0.4,0\n0,1,0.4,0.1\n0,2,0.4,0.2\n");
    CHECK(e.field() == "i_d_A");
    CHECK(e.message().find("at least two values") != std::string::npos);
    // A flux that stays flat along its own current (psi_d at i_q = 1 A, line 5) and one that falls
    // (psi_q at i_d = 1 A between i_q = 0 and 1 A, line 5).
    const std::string header = "i_d_A,i_q_A,psi_d_Vs,psi_q_Vs\n0,0,0.4,0\n0,1,0.4,0.1\n1,0,0.5,0\n";
    e = refusal(header + "1,1,0.4,0.1\n");
    CHECK(e.line() == 5);
    CHECK(e.field() == "psi_d_Vs");
    CHECK(e.message().find("psi_d stays from 0.4 Wb at i_d = 0 A to 0.4 Wb at i_d = 1 A (i_q = 1 A)") != std::string::npos);
    e = refusal(header + "1,1,0.6,-0.1\n");
    CHECK(e.line() == 5);
    CHECK(e.field() == "psi_q_Vs");
    CHECK(e.message().find("psi_q falls from 0 Wb at i_q = 0 A to -0.1 Wb at i_q = 1 A (i_d = 1 A)") != std::string::npos);
    // The same map with a rising flux is accepted.
    std::ofstream(path) << header + "1,1,0.6,0.1\n";
    CHECK_NOTHROW(FluxMap::read(path, 1.0));
}

TEST_CASE("the flux-map plant settles where the measured map says", "[pmsm][flux_map]") {
    const auto raw = raw_map();
    // Loads chosen so that the torque balance lands the currents on grid points.
    struct Point {
        double rpm, i_d, i_q;
    };
    const std::vector<Point> points{{200.0, -4.0, 8.0}, {-300.0, 0.0, -10.0}};
    std::vector<Segment> segments;
    for (const auto& p : points) {
        const auto& psi = raw.at({p.i_d, p.i_q});
        const double torque = 1.5 * 2 * (psi.first * p.i_q - psi.second * p.i_d);
        segments.push_back({"p", p.rpm, torque, p.i_d, 0.8, 20});
    }
    const auto drive = baldor_drive(segments);
    const auto result = simulate(drive);
    const FluxMap map = FluxMap::read(map_path, drive.motor.psi_f);
    const auto& m = result.data;
    for (std::size_t s = 0; s < points.size(); ++s) {
        const auto& rows = result.segments[s];
        const auto& p = points[s];
        const auto& psi = raw.at({p.i_d, p.i_q});
        const double omega = 2 * p.rpm * 2.0 * std::numbers::pi / 60.0;
        auto mean = [&](const Eigen::VectorXd& v) { return v.segment(rows.first_row, rows.rows).mean(); };
        // The controller is tuned with small-signal inductances the saturated machine does not have,
        // which leaves a slow tail (pole near R/L of the controller's model): the currents are on the
        // grid point to 1e-3 A, and every sample obeys the map at its own currents.
        CHECK(mean(m.i_d) == Approx(p.i_d).margin(1e-3));
        CHECK(mean(m.i_q) == Approx(p.i_q).margin(1e-3));
        CHECK(mean(m.omega_e) == Approx(omega).epsilon(2e-5));
        CHECK(mean(m.u_d) == Approx(0.63 * p.i_d - omega * psi.second).epsilon(1e-4));
        CHECK(mean(m.u_q) == Approx(0.63 * p.i_q + omega * psi.first).epsilon(1e-4));
        for (Eigen::Index k = rows.first_row; k < rows.first_row + rows.rows; ++k) {
            const Complex f = map.flux({m.i_d[k], m.i_q[k]}, drive.motor.psi_f);
            CHECK(m.u_d[k] == Approx(0.63 * m.i_d[k] - m.omega_e[k] * f.imag()).epsilon(1e-6));
            CHECK(m.u_q[k] == Approx(0.63 * m.i_q[k] + m.omega_e[k] * f.real()).epsilon(1e-6));
        }
    }
}

TEST_CASE("the saturation effect's law recovers the measured map", "[pmsm][flux_map][effects]") {
    std::vector<Segment> segments;
    for (double rpm : {200.0, -300.0})
        for (double i_d : {0.0, -4.0, 4.0})
            for (double torque : {3.0, 9.0, -9.0}) segments.push_back({"s", rpm, rpm > 0 ? torque : -torque, i_d, 0.2, 20});
    const auto result = simulate(baldor_drive(segments));
    const Eigen::Index n = result.data.size();
    Eigen::VectorXd y(2 * n);
    y << result.data.u_d, result.data.u_q;
    SteadyStateModel model(result.data, {});
    const auto base = solve_least_squares(linear_columns(model), y);
    const double base_rms = std::sqrt(base.rss / static_cast<double>(2 * n));
    FitOptions options;
    options.intervals = false;
    const auto saturating = fit_model(result.data, parse_model_spec("base+saturation"), options);
    const double saturating_rms = saturating.rms.total;
    INFO("rms residual: base model " << base_rms << " V, with saturation " << saturating_rms << " V");
    CHECK(saturating_rms * 10 < base_rms);
    // Generating points (negative torque at positive speed) keep R_s i_q apart from the part of psi_d
    // that is even in i_q: on motoring points alone both change sign with the direction, and R_s
    // absorbs the misfit of the d axis (6 % here when measured, 2026-11-25).
    CHECK(saturating.values[0] == Approx(0.63).epsilon(0.03));
    // ... and so do the map's magnet flux and small-signal q inductance.
    CHECK(saturating.values[3] == Approx(0.444146).epsilon(0.05));
    CHECK(saturating.values[2] == Approx((0.281523 - 0.0) / 2.0).epsilon(0.05));
}

TEST_CASE("on the measured map at high speed and large currents, what the saturation law cannot follow is its own error, not another effect",
          "[pmsm][flux_map][diagnosis]") {
    // One drive of the Baldor study's design high_large_quiet (experiments/pmsm/baldor_study.toml):
    // there the law leaves volts of structure, and before the laws' accuracy was stated an encoder
    // offset took a tenth of it in 16 of 20 drives. The rate is the study's; this is one example.
    const auto [data, d] = diagnosed_drive("baldor_study.toml", "high_large_quiet/clean");
    CHECK(d.recommended.text() == "base+saturation");
    const PathStep& last = d.path.back();
    CHECK(last.fit.spec.text() == "base+saturation");
    // The structure left is beyond the plain tolerance and within the law's stated 2 %.
    CHECK(last.structure > DiagnosisOptions{}.floor_tolerance);
    CHECK(last.at_noise_floor);
    CHECK_THAT(last.allowance.source, Catch::StartsWith("saturation (2 %"));
    // Then the intervals, which count only the noise, are marked not valid, in the flag and in words.
    CHECK(d.law_error_beyond_noise);
    CHECK_FALSE(d.recommended_intervals_valid());
    CHECK(std::any_of(d.findings.begin(), d.findings.end(), [](const std::string& f) {
        return f.find("within what the stated accuracy of the law of saturation") != std::string::npos && f.find("not valid") != std::string::npos;
    }));
    // The allowance from its definition: (0.02)^2 times the power of u - Rs i over the noise power.
    const double rs = last.fit.values[0];
    const double flux_voltage = (data.u_d - rs * data.i_d).squaredNorm() + (data.u_q - rs * data.i_q).squaredNorm();
    CHECK(last.allowance.power == Approx(0.0004 * flux_voltage / (static_cast<double>(data.size()) * d.noise.sigma.squaredNorm())).epsilon(1e-9));
    // The base model's own step states no allowance: the base law is exact by construction.
    CHECK(d.path.front().allowance.source.empty());
    CHECK(d.path.front().allowance.power == 0.0);
    // Nothing was added after the law, so nothing can stand in for it.
    CHECK(d.law_stand_ins.empty());
    // The design's three points at -950 r/min never reach that speed (logged at +217 to +235 rad/s,
    // i_q at the current limit, -28 to -31 A): they generate, so the power flows both ways and no
    // caveat says otherwise.
    CHECK(caveat_with(d, "every logged operating point") == nullptr);
}

TEST_CASE("on the measured map with every point motoring, the R_s interval says that R_s may take part of the saturation law's misfit "
          "(an example: one drive)",
          "[pmsm][flux_map][diagnosis]") {
    // Seed 1 of baldor_study's mid_large_quiet, whose R_s is 8 % off in the median over its 20 drives
    // (and within 1 % when its negative direction generates: baldor_generating_study).
    const auto [data, d] = diagnosed_drive("baldor_study.toml", "mid_large_quiet/clean");
    REQUIRE(d.recommended.text() == "base+saturation");
    for (const auto& s : d.segments) CHECK(s.omega * s.i_q > 0.0);
    const IntervalCaveat* power_flow = caveat_with(d, "every logged operating point motors");
    REQUIRE(power_flow != nullptr);
    CHECK(power_flow->reason.rfind("every logged operating point motors", 0) == 0);
    CHECK(power_flow->base == std::array<bool, 4>{true, false, false, false});
    CHECK(std::any_of(d.findings.begin(), d.findings.end(), [](const std::string& f) {
        return f.find("every logged operating point motors (its q current with its speed)") != std::string::npos;
    }));
    CHECK(d.recommended_interval_marked(0));
}

TEST_CASE("on the measured map with generating points, an effect added within the saturation law's stated error is named as a possible stand-in "
          "for the law's misfit (an example: one drive)",
          "[pmsm][flux_map][diagnosis]") {
    // One drive of experiments/pmsm/baldor_generating_study.toml, design mid_large_quiet: the plant
    // is the map and nothing else, and the search adds an encoder offset after saturation (in all 20
    // of the study's drives of this design; the rate is the study's, this is one example).
    const auto [data, d] = diagnosed_drive("baldor_generating_study.toml", "mid_large_quiet/clean");
    REQUIRE(d.recommended.text() == "base+saturation+encoder_offset");
    REQUIRE(d.law_stand_ins.size() == 1);
    const LawStandIn& s = d.law_stand_ins.front();
    CHECK(s.effect == "encoder_offset");
    CHECK_THAT(s.law, Catch::StartsWith("saturation (2 %"));
    // The step that added it, and the set it was added to.
    const auto added = std::find_if(d.path.begin(), d.path.end(), [](const PathStep& p) { return p.effect == "encoder_offset"; });
    REQUIRE(added != d.path.end());
    REQUIRE(added != d.path.begin());
    const ModelFit& before = std::prev(added)->fit;
    const ModelFit& after = added->fit;
    // The allowance from its definition: 2 % of u - Rs i, rms over the rows and axes, Rs of the set
    // the effect was added to.
    const double rs = before.values[0];
    const double flux_voltage = (data.u_d - rs * data.i_d).squaredNorm() + (data.u_q - rs * data.i_q).squaredNorm();
    CHECK(s.allowance_rms == Approx(0.02 * std::sqrt(flux_voltage / (2.0 * static_cast<double>(data.size())))).epsilon(1e-9));
    // What the addition changed in the prediction is at least what it took off the residual
    // (|r_b| - |r_a| <= |r_b - r_a|), and within the allowance, or it would not be named.
    CHECK(before.rms.total - after.rms.total <= s.change_rms * (1.0 + 1e-12));
    CHECK(s.change_rms > 0.0);
    CHECK(s.change_rms <= s.allowance_rms);
    CHECK(std::any_of(d.findings.begin(), d.findings.end(), [](const std::string& f) {
        return f.rfind("encoder_offset may stand in for the misfit of a law", 0) == 0 && f.find("saturation (2 % of the flux linkage)") != std::string::npos;
    }));
    // Its negative direction generates: the power flows both ways, and no caveat says it does not.
    CHECK(caveat_with(d, "every logged operating point") == nullptr);
}

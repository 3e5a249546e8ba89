#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <numbers>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "framework/optimizer.hpp"
#include "framework/random.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/fit/base_model_fit.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "tests/pmsm_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

const std::filesystem::path experiments = std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm";

// Simulates `spec` into work/<name>.csv with its sidecar and returns the CSV path.
std::filesystem::path simulated_file(const std::filesystem::path& work, const std::string& name, const DriveSimulation& spec) {
    const auto path = work / (name + ".csv");
    write_simulation(path, spec, simulate(spec), name);
    return path;
}

// The seed's two operating points with ideal sensors: 10 r/min, i_d = 0 then -0.1 A.
DriveSimulation quiet_paper_drive() {
    return quiet_drive({{"id0", 10.0, 0.1, 0.0, 0.8, 500}, {"id-0.1", 10.0, 0.1, -0.1, 0.4, 500}});
}

// Mean squared dq-voltage error of eq. (6), summed here sample by sample.
double direct_fitness(const Measurement& m, const Eigen::Vector4d& theta, double weight_d = 1.0, double weight_q = 1.0) {
    double sum = 0.0;
    for (Eigen::Index k = 0; k < m.size(); ++k) {
        const double ed = m.u_d[k] - (theta[0] * m.i_d[k] - theta[2] * m.omega_e[k] * m.i_q[k]);
        const double eq = m.u_q[k] - (theta[0] * m.i_q[k] + theta[1] * m.omega_e[k] * m.i_d[k] + theta[3] * m.omega_e[k]);
        sum += weight_d * ed * ed + weight_q * eq * eq;
    }
    return sum / static_cast<double>(m.size());
}

}  // namespace

TEST_CASE("on noise-free ideal data the least-squares optimum is the truth", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    const auto path = simulated_file(work, "quiet_paper", quiet_paper_drive());
    for (const std::string fitness : {"mse", "noise_weighted"}) {
        INFO("fitness " << fitness);
        const auto problem = make_problem("pmsm_identification", {{"data", path.string()}, {"fitness", fitness}});
        const auto& truth = problem->truth();
        REQUIRE(truth.true_parameters.has_value());
        CHECK(*truth.true_parameters == Eigen::Vector4d(46.0, 0.02025, 0.02025, 0.04375));
        REQUIRE(truth.reference_solution.has_value());
        const Eigen::VectorXd error = (*truth.reference_solution - *truth.true_parameters).cwiseQuotient(*truth.true_parameters);
        INFO("relative error " << error.transpose());
        CHECK(error.cwiseAbs().maxCoeff() < 1e-8);
        CHECK(truth.reference_label == "least-squares optimum");
        CHECK(*truth.optimum_value == *truth.reference_fitness);
        CHECK(problem->parameter_names() == std::vector<std::string>{"Rs", "Ld", "Lq", "psi_f"});
        CHECK(problem->bounds().lower == Eigen::Vector4d::Constant(1e-6));
        CHECK(problem->bounds().upper == Eigen::Vector4d(100, 10, 10, 10));
    }
    const auto problem = make_problem("pmsm_identification", {{"data", path.string()}});
    CHECK(*problem->truth().reference_fitness < 1e-18);
}

TEST_CASE("the batch evaluation equals the direct sum over samples", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    auto spec = quiet_paper_drive();
    spec.noise.current = 1e-3;
    spec.noise.speed = 0.02;
    spec.noise.voltage = 5e-3;
    spec.seed = 5;
    const auto path = simulated_file(work, "noisy_paper", spec);
    const Measurement data = read_measurement(path);
    const auto problem = make_problem("pmsm_identification", {{"data", path.string()}});

    Rng rng(9);
    Matrix x(4, 100);
    fill_uniform(x, problem->bounds(), rng);
    // Also candidates near the optimum, where cancellation would hurt the expanded quadratic.
    for (Eigen::Index j = 50; j < 100; ++j)
        for (Eigen::Index i = 0; i < 4; ++i)
            x(i, j) = (*problem->truth().reference_solution)[i] * (1.0 + 1e-3 * rng.normal());
    Vector f(100);
    problem->evaluate(x, f);

    Eigen::MatrixXd phi;
    Eigen::VectorXd y;
    base_regression(data, phi, y);
    const double n = static_cast<double>(data.size());
    const Eigen::Matrix4d a = phi.transpose() * phi;
    const Eigen::Vector4d b = phi.transpose() * y;
    const double c = y.squaredNorm();
    for (Eigen::Index j = 0; j < 100; ++j) {
        const Eigen::Vector4d theta = x.col(j);
        const double direct = direct_fitness(data, theta);
        CHECK(f[j] == Approx(direct).epsilon(1e-10));
        // The expanded quadratic is the same number up to cancellation of its c-sized terms.
        CHECK((theta.dot(a * theta) - 2 * b.dot(theta) + c) / n == Approx(direct).margin(1e-13 * c / n).epsilon(1e-10));
    }
    // The reference is the smallest value there is.
    CHECK(f.minCoeff() >= *problem->truth().reference_fitness);
    CHECK(*problem->truth().reference_fitness == Approx(direct_fitness(data, *problem->truth().reference_solution)).epsilon(1e-12));
}

TEST_CASE("the noise-weighted fitness divides each axis by its residual variance", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    auto spec = quiet_paper_drive();
    spec.noise.voltage = 0.002;  // logged-voltage noise dominates on d ...
    spec.noise.current = 1e-4;
    spec.seed = 6;
    auto result = simulate(spec);
    // ... and an extra, larger error on q makes the axes differ.
    Rng rng(2);
    for (Eigen::Index k = 0; k < result.data.size(); ++k) result.data.u_q[k] += 0.1 * rng.normal();
    const auto path = work / "weighted.csv";
    write_measurement(path, result.data);
    const auto problem = make_problem("pmsm_identification", {{"data", path.string()}, {"fitness", std::string("noise_weighted")}});

    // The weights from an independent unweighted solution (SVD) and its per-axis residuals.
    Eigen::MatrixXd phi;
    Eigen::VectorXd y;
    base_regression(result.data, phi, y);
    const Eigen::VectorXd plain = phi.jacobiSvd(Eigen::ComputeThinU | Eigen::ComputeThinV).solve(y);
    const Eigen::VectorXd r = y - phi * plain;
    const Eigen::Index n = result.data.size();
    const double var_d = r.head(n).squaredNorm() / static_cast<double>(n), var_q = r.tail(n).squaredNorm() / static_cast<double>(n);
    CHECK(var_q > 20 * var_d);

    Matrix x(4, 3);
    x.col(0) = Eigen::Vector4d(46.0, 0.02025, 0.02025, 0.04375);
    x.col(1) = Eigen::Vector4d(45.0, 0.03, 0.01, 0.045);
    x.col(2) = *problem->truth().reference_solution;
    Vector f(3);
    problem->evaluate(x, f);
    for (int j = 0; j < 3; ++j) CHECK(f[j] == Approx(direct_fitness(result.data, x.col(j), 1.0 / var_d, 1.0 / var_q)).epsilon(1e-9));
    // At its own optimum each axis contributes about one per sample.
    CHECK(f[2] == Approx(2.0).epsilon(0.01));
    CHECK_FALSE(problem->truth().true_parameters.has_value());  // no sidecar was written
}

TEST_CASE("settle drops the samples right after each segment start", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    auto spec = quiet_paper_drive();
    spec.segments[1].settle = 0.0;  // log the i_d step itself
    spec.segments[1].samples = 400;
    const auto path = simulated_file(work, "unsettled", spec);
    const auto all = make_problem("pmsm_identification", {{"data", path.string()}});
    const auto settled = make_problem("pmsm_identification", {{"data", path.string()}, {"settle", 0.1}});
    // The current step leaves L di/dt in the first milliseconds, which the model lacks, and a small
    // speed-loop transient (double pole at 10 Hz) after it.
    CHECK(*all->truth().reference_fitness > 1e-6);
    INFO(settled->describe());
    CHECK(*settled->truth().reference_fitness < 1e-16);
    CHECK(settled->describe().find("400 of 900 samples") != std::string::npos);
    const auto& truth = *settled->truth().true_parameters;
    CHECK(((*settled->truth().reference_solution - truth).cwiseQuotient(truth)).cwiseAbs().maxCoeff() < 1e-6);
}

TEST_CASE("the reference stays inside Table 2's box and says which bound holds it", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    // Data whose unconstrained fit has a negative Lq: u_d = +omega Lq i_q instead of minus.
    Measurement m;
    const Eigen::Index n = 400;
    m.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
        const bool injected = k >= n / 2;
        m.i_d[k] = injected ? -0.1 : 0.0;
        m.i_q[k] = 0.095 + 1e-3 * std::sin(0.1 * k);
        m.omega_e[k] = 16.76;
        m.u_d[k] = 46.0 * m.i_d[k] + 16.76 * 0.02 * m.i_q[k];
        m.u_q[k] = 46.0 * m.i_q[k] + 16.76 * 0.02 * m.i_d[k] + 16.76 * 0.044 + 1e-3 * std::cos(0.37 * k);
    }
    const auto path = work / "negative_lq.csv";
    write_measurement(path, m);
    const auto problem = make_problem("pmsm_identification", {{"data", path.string()}});
    const auto& ref = *problem->truth().reference_solution;
    CHECK(ref[2] == 1e-6);
    CHECK(problem->truth().reference_label == "least-squares optimum (inside Table 2's box: Lq at its lower bound)");
    // No point of the box does better.
    Rng rng(4);
    Matrix x(4, 2000);
    fill_uniform(x, problem->bounds(), rng);
    for (Eigen::Index j = 1000; j < 2000; ++j) {
        x.col(j) = ref + 1e-4 * ref.cwiseProduct(Eigen::Vector4d(rng.normal(), rng.normal(), rng.normal(), rng.normal()));
        clamp_to_bounds(x.col(j), problem->bounds());
    }
    Vector f(2000);
    problem->evaluate(x, f);
    CHECK(f.minCoeff() >= *problem->truth().reference_fitness);
}

TEST_CASE("pmsm_identification refuses what it cannot fit", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    CHECK_THROWS_AS(make_problem("pmsm_identification"), ParameterError);
    CHECK_THROWS_AS(make_problem("pmsm_identification", {{"data", std::string("no_such_file.csv")}}, {work, 0, nullptr}), InputError);
    CHECK_THROWS_AS(make_problem("pmsm_identification", {{"fitness", std::string("mae")}, {"data", std::string("x.csv")}}),
                    ParameterError);
    // Relative paths resolve against the context's base directory.
    const auto path = simulated_file(work, "relative", quiet_drive({{"a", 10.0, 0.1, 0.0, 0.5, 10}, {"b", 10.0, 0.1, -0.1, 0.2, 10}}));
    CHECK_NOTHROW(make_problem("pmsm_identification", {{"data", path.filename().string()}}, {work, 0, nullptr}));
    Measurement bare = read_measurement(path);
    bare.t.reset();
    write_measurement(work / "no_time.csv", bare);
    try {
        make_problem("pmsm_identification", {{"data", (work / "no_time.csv").string()}, {"settle", 0.01}});
        FAIL("settle without a time column was accepted");
    } catch (const InputError& e) {
        CHECK(e.field() == "settle");
    }
    CHECK_THROWS_AS(make_problem("pmsm_identification", {{"data", path.string()}, {"settle", 1.0}}), InputError);
}

TEST_CASE("with the seed's two operating points and realistic noise Ld and Lq are poorly determined",
          "[pmsm][identification]") {
    const auto paper = simulate(read_simulation_profile(experiments / "paper_profile.toml"));
    const auto multi = simulate(read_simulation_profile(experiments / "multi_point_profile.toml"));
    const auto two = fit_base_model(paper.data, Fitness::MeanSquared, CovarianceMethod::NeweyWest);
    const auto many = fit_base_model(multi.data, Fitness::MeanSquared, CovarianceMethod::NeweyWest);
    auto half_width = [](const BaseModelFit& fit) {
        return Eigen::Vector4d(fit.uncertainty.critical_value * fit.uncertainty.standard_error.cwiseQuotient(fit.least_squares.solution));
    };
    const Eigen::Vector4d w2 = half_width(two), wm = half_width(many);
    INFO("relative 95 % half-widths, two points: " << w2.transpose() << "; ten points: " << wm.transpose());
    // The inductances ride on millivolts: about ±10 % and more, while Rs and psi_f are known to 1 %.
    CHECK(w2[1] > 0.08);
    CHECK(w2[2] > 0.08);
    CHECK(w2[0] < 0.01);
    CHECK(w2[3] < 0.02);
    // More operating points (two speeds, both directions, three d currents) narrow them several-fold.
    CHECK(wm[1] < w2[1] / 2.5);
    CHECK(wm[2] < w2[2] / 2.5);
}

TEST_CASE("a box set by the experiment moves the reference optimum to the box's edge", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    const auto path = simulated_file(work, "quiet_paper_box", quiet_paper_drive());
    auto problem = make_problem("pmsm_identification", {{"data", path.string()}});
    const Eigen::Vector4d unconstrained = *problem->truth().reference_solution;
    REQUIRE(unconstrained[0] == Approx(46.0).epsilon(1e-6));
    Eigen::Vector4d lower = problem->bounds().lower, upper = problem->bounds().upper;
    upper[0] = 45.0;  // exclude the true Rs
    problem->override_bounds(lower, upper);
    const auto& truth = problem->truth();
    REQUIRE((*truth.reference_solution)[0] == 45.0);
    REQUIRE_THAT(truth.reference_label, Catch::Contains("Rs at its upper bound"));
    // The new reference is the best point of the new box: its fitness is below that of nearby points inside it.
    Matrix x(4, 3);
    x.col(0) = *truth.reference_solution;
    x.col(1) = *truth.reference_solution;
    x(0, 1) = 44.9;
    x.col(2) = *truth.reference_solution;
    x(1, 2) *= 1.01;
    Vector f(3);
    problem->evaluate(x, f);
    REQUIRE(f[0] == Approx(*truth.reference_fitness).epsilon(1e-9));
    REQUIRE(f[0] < f[1]);
    REQUIRE(f[0] < f[2]);
}

TEST_CASE("the instances of one experiment read the measurement once and share its statistics", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    const auto path = simulated_file(work, "quiet_paper", quiet_paper_drive());
    ProblemContext context{work, 0, std::make_shared<SharedProblemData>()};
    const auto first = make_problem("pmsm_identification", {{"data", path.string()}}, context);
    // The file is gone: a second instance can only come from what the first one built.
    std::filesystem::remove(path);
    const auto second = make_problem("pmsm_identification", {{"data", path.string()}}, context);
    CHECK(context.shared->builds() == 1);
    CHECK(second->truth().reference_solution == first->truth().reference_solution);
    CHECK(second->describe() == first->describe());
    Matrix x(4, 1);
    x.col(0) = *first->truth().reference_solution;
    Vector f1(1), f2(1);
    first->evaluate(x, f1);
    second->evaluate(x, f2);
    CHECK(f1[0] == f2[0]);
    // Other parameters are other statistics: built anew (and here refused, since the file is gone).
    CHECK_THROWS_AS(make_problem("pmsm_identification", {{"data", path.string()}, {"settle", 0.1}}, context), InputError);
    // Outside an experiment each instance builds its own.
    CHECK_THROWS_AS(make_problem("pmsm_identification", {{"data", path.string()}}, ProblemContext{work, 0, nullptr}), InputError);
}

TEST_CASE("a column map in the problem's parameters reads a log with its own names and units", "[pmsm][identification]") {
    const mhb::testing::TemporaryDirectory work_directory;
    const auto& work = work_directory.path();
    const auto path = simulated_file(work, "quiet_paper", quiet_paper_drive());
    const Measurement m = read_measurement(path);
    // The same log as a bench might write it: its own names, currents in mA, speed in rpm of a
    // 16-pole-pair machine.
    std::ofstream out(work / "bench.csv");
    out << "time,op,Id,Iq,Vd,Vq,n\n";
    for (Eigen::Index k = 0; k < m.size(); ++k)
        out << fmt::format("{:.17g},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", (*m.t)[k], m.segment_labels[static_cast<std::size_t>(m.segment[k])],
                           1e3 * m.i_d[k], 1e3 * m.i_q[k], m.u_d[k], m.u_q[k], m.omega_e[k] / 16.0 * 60.0 / (2.0 * std::numbers::pi));
    out.close();
    {
        std::ofstream map(work / "bench_columns.toml");
        map << "pole_pairs = 16\n[columns]\nomega_e = \"n[rpm]\"\n";
    }
    const auto original = make_problem("pmsm_identification", {{"data", path.string()}});
    const auto mapped = make_problem(
        "pmsm_identification",
        {{"data", std::string("bench.csv")}, {"columns", std::string("t=time,segment=op,i_d=Id[mA],i_q=Iq[mA],u_d=Vd,u_q=Vq")},
         {"columns_file", std::string("bench_columns.toml")}},
        {work, 0, nullptr});
    const Eigen::VectorXd expected = *original->truth().reference_solution, got = *mapped->truth().reference_solution;
    for (Eigen::Index j = 0; j < 4; ++j) CHECK(got[j] == Approx(expected[j]).epsilon(1e-9));
    // Without the pole-pair count an rpm column cannot be read: refused, naming the column.
    try {
        make_problem("pmsm_identification", {{"data", std::string("bench.csv")}, {"columns", std::string("omega_e=n[rpm]")}}, {work, 0, nullptr});
        FAIL("an rpm column without a pole-pair count was accepted");
    } catch (const InputError& e) {
        CHECK(std::string(e.what()).find("pole") != std::string::npos);
        CHECK(e.field() == "omega_e");
    }
}

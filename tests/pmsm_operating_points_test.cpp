// The operating-point finder (problems/pmsm/data/operating_points.hpp) on signals made by hand:
// piecewise constant with known change rows, pure noise, filtered noise.
#include <random>

#include <catch2/catch.hpp>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/operating_points.hpp"

using namespace mhb::pmsm;

namespace {

struct Piecewise {
    Eigen::MatrixXd x;
    std::vector<Eigen::Index> starts;  // first row of each level
};

// Levels held for the given row counts on `channels` channels; at each change one channel, in
// turn, steps by `step` noise standard deviations (the others keep their level, as a d-current
// step leaves the speed), with white noise of standard deviation `sigma`.
Piecewise piecewise(const std::vector<Eigen::Index>& lengths, int channels, double step, double sigma, std::mt19937_64& random) {
    std::normal_distribution<double> normal;
    Eigen::Index n = 0;
    for (auto l : lengths) n += l;
    Piecewise p;
    p.x.resize(n, channels);
    Eigen::VectorXd level = Eigen::VectorXd::LinSpaced(channels, 1.0, 3.0);
    Eigen::Index row = 0;
    for (std::size_t s = 0; s < lengths.size(); ++s) {
        if (s > 0) level[static_cast<Eigen::Index>(s % static_cast<std::size_t>(channels))] += (s % 2 ? 1.0 : -1.0) * step * sigma;
        p.starts.push_back(row);
        for (Eigen::Index k = 0; k < lengths[s]; ++k, ++row)
            for (int c = 0; c < channels; ++c) p.x(row, c) = level[c] + sigma * normal(random);
    }
    return p;
}

}  // namespace

TEST_CASE("pure noise has no change point at about the stated false-alarm rate", "[pmsm][operating_points]") {
    std::mt19937_64 random(20261125);
    std::normal_distribution<double> normal;
    const int logs = 400;
    int false_alarms = 0;
    for (int k = 0; k < logs; ++k) {
        Eigen::MatrixXd x(2000, 3);
        for (Eigen::Index r = 0; r < x.rows(); ++r)
            for (int c = 0; c < 3; ++c) x(r, c) = 0.3 * normal(random);
        const auto points = find_steady_windows(x);
        if (points.windows.size() != 1 || points.transient_rows != 0) ++false_alarms;
    }
    // The stated 1 % is asymptotic; at 2000 rows the Gumbel limit is conservative, and 3 % bounds
    // the binomial spread of 400 logs at 1 % (mean 4, sd 2) with room for a modest excess.
    INFO("logs with a false change: " << false_alarms << " of " << logs);
    CHECK(false_alarms <= 12);
}

TEST_CASE("filtered noise, as a logging filter makes it, gives no more false changes than white noise", "[pmsm][operating_points]") {
    std::mt19937_64 random(7);
    std::normal_distribution<double> normal;
    int false_alarms = 0;
    const int logs = 200;
    for (int k = 0; k < logs; ++k) {
        Eigen::MatrixXd x(3000, 3);
        Eigen::RowVector3d state = Eigen::RowVector3d::Zero();
        for (Eigen::Index r = 0; r < x.rows(); ++r) {
            for (int c = 0; c < 3; ++c) state[c] = 0.8 * state[c] + 0.2 * normal(random);
            x.row(r) = state;
        }
        const auto points = find_steady_windows(x);
        if (points.windows.size() != 1) ++false_alarms;
    }
    INFO("logs with a false change: " << false_alarms << " of " << logs);
    CHECK(false_alarms <= 6);
}

TEST_CASE("steps of a few noise deviations are found with their rows", "[pmsm][operating_points]") {
    std::mt19937_64 random(99);
    std::uniform_int_distribution<Eigen::Index> length(60, 400);
    for (double step : {4.0, 6.0, 20.0}) {
        const int runs = 100;
        int counted = 0, within_two = 0, within_bandwidth = 0;
        for (int k = 0; k < runs; ++k) {
            std::vector<Eigen::Index> lengths;
            for (int s = 0; s < 8; ++s) lengths.push_back(length(random));
            const auto p = piecewise(lengths, 3, step, 0.05, random);
            const auto points = find_steady_windows(p.x);
            if (points.windows.size() != lengths.size()) continue;
            ++counted;
            Eigen::Index error = 0;
            for (std::size_t s = 0; s < lengths.size(); ++s) {
                error = std::max(error, std::abs(points.windows[s].first - p.starts[s]));
                error = std::max(error, std::abs(points.windows[s].first + points.windows[s].rows - p.starts[s] - lengths[s]));
            }
            if (error <= 2) ++within_two;
            if (error <= 10) ++within_bandwidth;
        }
        INFO("step " << step << " sd: " << counted << " of " << runs << " logs with the right count, all 16 boundaries within 2 rows in "
                     << within_two << ", within 10 rows in " << within_bandwidth);
        if (step >= 6.0) {
            // Clear steps: every one found (a log may still get its 1 % false alarm), and placed to
            // the row by the row test.
            CHECK(counted >= runs * 95 / 100);
            CHECK(within_two >= counted * 95 / 100);
        } else {
            // A step of 4 sd is near the edge of what windows of 10 rows tell (its expected
            // statistic 4 sqrt(10/2) = 8.9 against a threshold near 5) and of the row test (4 sd):
            // most logs get all, and the moving sum's peak places each within G rows.
            CHECK(counted >= runs * 8 / 10);
            CHECK(within_bandwidth >= counted * 9 / 10);
        }
        CHECK(true);
    }
}

TEST_CASE("a ramp and an exponential settling are transient, the levels either side steady", "[pmsm][operating_points]") {
    std::mt19937_64 random(3);
    std::normal_distribution<double> normal;
    // 300 steady rows, a 100-row ramp of 40 sd, 300 steady rows, a step followed by a settling with
    // a time constant of 30 rows, 300 steady rows.
    const double sigma = 0.01;
    std::vector<double> signal;
    for (int k = 0; k < 300; ++k) signal.push_back(0.0);
    for (int k = 0; k < 100; ++k) signal.push_back(0.4 * (k + 1) / 100.0);
    for (int k = 0; k < 300; ++k) signal.push_back(0.4);
    for (int k = 0; k < 500; ++k) signal.push_back(0.2 + 0.5 * std::exp(-k / 30.0));
    Eigen::MatrixXd x(static_cast<Eigen::Index>(signal.size()), 1);
    for (Eigen::Index r = 0; r < x.rows(); ++r) x(r, 0) = signal[static_cast<std::size_t>(r)] + sigma * normal(random);
    const auto points = find_steady_windows(x);
    REQUIRE(points.windows.size() == 3);
    // A ramp's first and last rows are at its levels within the noise: a window may reach into it
    // until the ramp is 4 sd away, 4 sigma / slope = 10 rows, never further.
    const Eigen::Index ramp_rows = 10;
    CHECK(points.windows[0].first + points.windows[0].rows >= 300 - 2);
    CHECK(points.windows[0].first + points.windows[0].rows <= 300 + ramp_rows + 2);
    CHECK(points.windows[1].first >= 400 - ramp_rows - 2);
    CHECK(points.windows[1].first <= 400 + 2);
    CHECK(std::abs(points.windows[1].first + points.windows[1].rows - 700) <= 2);
    // The window's head of H = 40 rows is compared with its tail while the settling moves the head's
    // mean by more than the threshold D (about 5) at that scale, D sigma sqrt(2/H) = 0.011:
    // 0.5 e^(-k/30) (30/40) (1 - e^(-40/30)) > 0.011 up to k = 97, and the start moves in steps of
    // G = 10 rows; it never starts before the moving sum of 10 rows stops seeing it (k = 45).
    const Eigen::Index settled = points.windows[2].first - 700;
    CHECK(settled >= 45);
    CHECK(settled <= 97 + 10 + 2);
    CHECK(points.windows[2].first + points.windows[2].rows == x.rows());
}

TEST_CASE("a log whose levels never hold for the shortest window is refused naming the file", "[pmsm][operating_points]") {
    Measurement m;
    m.source = "ramp.csv";
    m.resize(200);
    std::mt19937_64 random(1);
    std::normal_distribution<double> normal;
    for (Eigen::Index r = 0; r < 200; ++r) {
        m.i_d[r] = 0.001 * normal(random);
        // A new level every 20 rows, shorter than the 30 rows a window needs.
        m.i_q[r] = 0.1 * static_cast<double>(r / 20) + 0.001 * normal(random);
        m.u_d[r] = m.u_q[r] = 1.0;
        m.omega_e[r] = 100.0 + 0.01 * normal(random);
    }
    const auto points = find_operating_points(m);
    CHECK(points.windows.empty());
    CHECK_THROWS_AS(select_operating_points(std::move(m), points), mhb::InputError);
}

TEST_CASE("the found windows become segments of the selected rows", "[pmsm][operating_points]") {
    std::mt19937_64 random(5);
    const auto p = piecewise({200, 300, 250}, 3, 30.0, 0.02, random);
    Measurement m;
    m.resize(p.x.rows());
    m.i_d = p.x.col(0);
    m.i_q = p.x.col(1);
    m.omega_e = p.x.col(2);
    m.u_d.setOnes();
    m.u_q.setOnes();
    const auto points = find_operating_points(m);
    REQUIRE(points.windows.size() == 3);
    const auto steady = select_operating_points(std::move(m), points);
    CHECK(steady.segment_labels == std::vector<std::string>{"steady1", "steady2", "steady3"});
    CHECK(steady.size() + points.transient_rows == p.x.rows());
    CHECK(steady.segment[0] == 0);
    CHECK(steady.segment[steady.size() - 1] == 2);
}

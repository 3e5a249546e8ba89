// ISOA's third strategy in isolation: the Lévy steps (eq. 18), the Cauchy step factors (eq. 22),
// the Lehmer-mean update of mu (eq. 23) and the two cuckoo passes (eq. 24-25).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <boost/math/distributions/cauchy.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/math/tools/roots.hpp>

#include "optimizers/snake/cauchy_cuckoo_search.hpp"

using namespace mhb;

namespace {

// P(L <= x) for L = u / |v|^(1/beta), u ~ N(0, sd^2), v ~ N(0, 1): conditioning on v,
// P(L <= x) = E[Phi(x |v|^(1/beta) / sd)] = 2 int_0^inf phi(v) Phi(x v^(1/beta) / sd) dv.
double levy_cdf(double x, double sd, double beta) {
    const boost::math::normal standard;
    auto integrand = [&](double v) {
        return 2.0 * boost::math::pdf(standard, v) * boost::math::cdf(standard, x * std::pow(v, 1.0 / beta) / sd);
    };
    return boost::math::quadrature::gauss_kronrod<double, 61>::integrate(
        integrand, 0.0, std::numeric_limits<double>::infinity(), 15, 1e-12);
}

Matrix uniform_matrix(Eigen::Index rows, Eigen::Index cols, Rng& rng) {
    Matrix m(rows, cols);
    for (auto& v : m.reshaped()) v = rng.uniform(-1.0, 1.0);
    return m;
}

double fraction_below(const std::vector<double>& sample, double x) {
    return static_cast<double>(std::count_if(sample.begin(), sample.end(), [x](double s) { return s <= x; })) /
           static_cast<double>(sample.size());
}

// Five standard deviations of an empirical CDF at probability p from n draws.
double tolerance(double p, std::size_t n) { return 5.0 * std::sqrt(p * (1.0 - p) / static_cast<double>(n)); }

}  // namespace

TEST_CASE("Mantegna's sigma for beta = 1.5 is 0.696574", "[cauchy_cuckoo_search]") {
    REQUIRE(mantegna_sigma(1.5) == Approx(0.696574).margin(1e-6));
    REQUIRE(mantegna_sigma(1.0) == Approx(1.0));  // beta = 1: Gamma(2) sin(pi/2) / Gamma(1) = 1
}

TEST_CASE("Lévy steps have the distribution of u/|v|^(2/3) with sd(u) = 0.696574", "[cauchy_cuckoo_search]") {
    const double sigma = mantegna_sigma(1.5);
    Rng rng(11);
    std::vector<double> steps(200000), magnitudes(steps.size());
    for (std::size_t k = 0; k < steps.size(); ++k) {
        steps[k] = mantegna_step(rng, sigma, 1.5);
        magnitudes[k] = std::abs(steps[k]);
    }
    for (double x : {-10.0, -2.0, -0.5, 0.0, 0.3, 1.0, 4.0, 50.0}) {
        const double expected = levy_cdf(x, sigma, 1.5);
        INFO("x = " << x);
        REQUIRE(fraction_below(steps, x) == Approx(expected).margin(tolerance(expected, steps.size())));
    }
    // The median m of |L| solves 2 F(m) - 1 = 1/2.
    const auto [lo, hi] = boost::math::tools::bisect([&](double m) { return 2.0 * levy_cdf(m, sigma, 1.5) - 1.5; }, 0.01,
                                                      100.0, boost::math::tools::eps_tolerance<double>(40));
    const double median = 0.5 * (lo + hi);
    REQUIRE(fraction_below(magnitudes, median) == Approx(0.5).margin(tolerance(0.5, magnitudes.size())));
    // The check has power: reading 0.6966 as a variance (sd 0.8346) moves F(1) by far more than
    // the tolerance (0.033 against 0.0045).
    REQUIRE(std::abs(levy_cdf(1.0, std::sqrt(0.696574), 1.5) - levy_cdf(1.0, sigma, 1.5)) >
            5 * tolerance(0.8, steps.size()));
}

TEST_CASE("eq. (22) draws Cauchy(mu, 0.1)", "[cauchy_cuckoo_search]") {
    Rng rng(12);
    const boost::math::cauchy_distribution<double> reference(0.5, 0.1);
    std::vector<double> draws(200000);
    for (auto& a : draws) a = cauchy_step_factor(rng, 0.5);
    for (double p : {0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99}) {
        INFO("p = " << p);
        REQUIRE(fraction_below(draws, boost::math::quantile(reference, p)) == Approx(p).margin(tolerance(p, draws.size())));
    }
    // The raw draws are negative with probability F(0) = 1/2 - atan(5)/pi = 0.0628.
    const double negative = boost::math::cdf(reference, 0.0);
    REQUIRE(negative == Approx(0.5 - std::atan(5.0) / std::numbers::pi));
    std::vector<double> raw(200000);
    for (auto& a : raw) a = step_factor(rng, 0.5, CauchyAlphaRule::Raw);
    REQUIRE(fraction_below(raw, 0.0) == Approx(negative).margin(tolerance(negative, raw.size())));
}

TEST_CASE("the JADE rule gives Cauchy(mu, 0.1) conditioned on > 0 and cut at 1", "[cauchy_cuckoo_search]") {
    Rng rng(13);
    const double mu = 0.7;
    const boost::math::cauchy_distribution<double> c(mu, 0.1);
    const double f0 = boost::math::cdf(c, 0.0);
    std::vector<double> draws(200000);
    for (auto& a : draws) a = step_factor(rng, mu, CauchyAlphaRule::Jade);
    REQUIRE(*std::min_element(draws.begin(), draws.end()) > 0.0);
    REQUIRE(*std::max_element(draws.begin(), draws.end()) == 1.0);
    for (double x : {0.2, 0.5, 0.7, 0.9, 0.999}) {
        const double expected = (boost::math::cdf(c, x) - f0) / (1.0 - f0);
        INFO("x = " << x);
        REQUIRE(fraction_below(draws, x) == Approx(expected).margin(tolerance(expected, draws.size())));
    }
    const double at_one = (1.0 - boost::math::cdf(c, 1.0)) / (1.0 - f0);
    const double ones = static_cast<double>(std::count(draws.begin(), draws.end(), 1.0)) / static_cast<double>(draws.size());
    REQUIRE(ones == Approx(at_one).margin(tolerance(at_one, draws.size())));
}

TEST_CASE("Lehmer mean and eq. (23) on a hand-computed example", "[cauchy_cuckoo_search]") {
    // {0.2, 0.5, 0.9}: sum of squares 1.10, sum 1.6, Lehmer mean 0.6875;
    // mu = 0.1 * 0.5 + 0.9 * 0.6875 = 0.66875 (the paper's weights); JADE's: 0.9 * 0.5 + 0.1 * 0.6875.
    const double values[] = {0.2, 0.5, 0.9};
    REQUIRE(lehmer_mean(values, 3) == Approx(0.6875));
    REQUIRE(updated_location(0.5, 0.1, 0.6875) == Approx(0.66875));
    REQUIRE(updated_location(0.5, 0.9, 0.6875) == Approx(0.51875));
}

TEST_CASE("mu moves to the Lehmer mean of the accepted Lévy moves only", "[cauchy_cuckoo_search]") {
    Bounds box{Vector::Constant(2, -1e6), Vector::Constant(2, 1e6)};
    CauchyCuckooSearch cuckoo({0.5, 0.1, 0.25, CauchyAlphaRule::Jade});
    cuckoo.resize(2, 6);
    Rng rng(14);
    Matrix nests = uniform_matrix(2, 6, rng);
    Vector fitness = Vector::Constant(6, 10.0);
    const Vector best = nests.col(3);
    Matrix candidates(2, 6);
    cuckoo.propose_levy(nests, best, box, rng, candidates);
    // The best nest steps by alpha (x - best) L = 0: it stays put.
    REQUIRE(candidates.col(3) == nests.col(3));
    const Vector alpha = cuckoo.alphas();
    // Nests 0, 2 and 5 improve; nest 1 ties (not a success), the others get worse.
    Vector candidate_fitness(6);
    candidate_fitness << 1.0, 10.0, 2.0, 11.0, 12.0, 3.0;
    REQUIRE(cuckoo.accept_levy(nests, fitness, candidates, candidate_fitness) == 3);
    const double chosen[] = {alpha[0], alpha[2], alpha[5]};
    const double expected = 0.1 * 0.5 + 0.9 * (chosen[0] * chosen[0] + chosen[1] * chosen[1] + chosen[2] * chosen[2]) /
                                            (chosen[0] + chosen[1] + chosen[2]);
    REQUIRE(cuckoo.mu() == Approx(expected));
    REQUIRE(nests.col(0) == candidates.col(0));
    REQUIRE(fitness[1] == 10.0);
    // No success: mu stays.
    cuckoo.propose_levy(nests, best, box, rng, candidates);
    REQUIRE(cuckoo.accept_levy(nests, fitness, candidates, Vector::Constant(6, 100.0)) == 0);
    REQUIRE(cuckoo.mu() == Approx(expected));
}

TEST_CASE("the discovery pass moves i by r (x_p - x_q), p != q, both != i, one r per pass", "[cauchy_cuckoo_search]") {
    // Three nests on a line at 0, 1 and 3: the only admissible pairs give |x_p - x_q| = 2 for nest 0,
    // 3 for nest 1 and 1 for nest 2, so with a shared r the moves stand exactly in ratio 2 : 3 : 1.
    Bounds box{Vector::Constant(1, -100.0), Vector::Constant(1, 100.0)};
    CauchyCuckooSearch cuckoo({0.5, 0.1, 0.0, CauchyAlphaRule::Jade});
    cuckoo.resize(1, 3);
    Rng rng(15);
    Matrix nests(1, 3);
    nests << 0.0, 1.0, 3.0;
    Matrix out(1, 3);
    for (int pass = 0; pass < 200; ++pass) {
        cuckoo.propose_discovery(nests, box, rng, out);
        const Eigen::ArrayXd step = (out - nests).row(0).transpose().array().abs();
        if (step[2] < 1e-9) continue;  // r = 0 (never in practice)
        REQUIRE(step[0] / step[2] == Approx(2.0));
        REQUIRE(step[1] / step[2] == Approx(3.0));
    }
    // With p_a = 0.25 a coordinate moves with probability 0.75.
    CauchyCuckooSearch partial({0.5, 0.1, 0.25, CauchyAlphaRule::Jade});
    partial.resize(50, 10);
    Bounds wide{Vector::Constant(50, -100.0), Vector::Constant(50, 100.0)};
    Matrix many = uniform_matrix(50, 10, rng), moved(50, 10);
    long count = 0, total = 0;
    for (int pass = 0; pass < 100; ++pass) {
        partial.propose_discovery(many, wide, rng, moved);
        count += ((moved - many).array() != 0.0).count();
        total += many.size();
    }
    REQUIRE(static_cast<double>(count) / static_cast<double>(total) == Approx(0.75).margin(tolerance(0.75, 50000)));
}

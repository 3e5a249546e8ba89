#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <boost/math/distributions/cauchy.hpp>
#include <boost/math/distributions/normal.hpp>

#include "framework/random.hpp"

using mhb::Rng;

TEST_CASE("xoshiro256++ reproduces the reference implementation's output stream", "[random]") {
    // State s = {0, 0, 0, 1} run through Blackman and Vigna's xoshiro256plusplus.c: its first ten
    // outputs (as published with an independent port's test data).
    mhb::Rng rng;
    rng.set_state(0, 0, 0, 1);
    const std::uint64_t expected[] = {0x0000000000800000ULL, 0x0000000000800011ULL, 0x0002200000800011ULL, 0x0002200044000020ULL,
                                      0x00022000448008A1ULL, 0x01102100802208A0ULL, 0x0114002284200880ULL, 0x0402896644A64095ULL,
                                      0x8A14A0A244ACC891ULL, 0x8C88BA4680B20495ULL};
    for (std::uint64_t value : expected) REQUIRE(rng() == value);
}

TEST_CASE("one seed gives one stream, and neighbouring seeds differ", "[random]") {
    Rng a(42), b(42), c(43);
    int equal_to_neighbour = 0;
    for (int i = 0; i < 1000; ++i) {
        const auto va = a();
        REQUIRE(va == b());
        equal_to_neighbour += va == c() ? 1 : 0;
    }
    REQUIRE(equal_to_neighbour == 0);
}

TEST_CASE("FNV-1a, which names seeds, reproduces its published test vectors", "[random]") {
    REQUIRE(mhb::stable_hash("") == 0xCBF29CE484222325ULL);
    REQUIRE(mhb::stable_hash("a") == 0xAF63DC4C8601EC8CULL);
    REQUIRE(mhb::stable_hash("foobar") == 0x85944171F73967E8ULL);
}

TEST_CASE("SplitMix64 reproduces its published first value", "[random]") {
    // SplitMix64 with state 0 first returns 0xE220A8397B1DCDAF (Vigna's reference implementation).
    std::uint64_t state = 0;
    REQUIRE(mhb::splitmix64(state) == 0xE220A8397B1DCDAFULL);
}

TEST_CASE("derived seeds depend on every component", "[random]") {
    std::set<std::uint64_t> seeds;
    for (std::uint64_t master : {1ULL, 2ULL})
        for (const char* opt : {"gwo", "soa"})
            for (const char* prob : {"F1", "F2"})
                for (std::uint64_t t = 0; t < 10; ++t) seeds.insert(mhb::derive_seed(master, opt, prob, t));
    REQUIRE(seeds.size() == 2 * 2 * 2 * 10);
}

namespace {
// Empirical quantile of a sorted sample.
double quantile(const std::vector<double>& sorted, double p) {
    return sorted[static_cast<std::size_t>(p * static_cast<double>(sorted.size() - 1))];
}
}  // namespace

TEST_CASE("uniform, normal and Cauchy draws follow their distributions (quantiles)", "[random]") {
    Rng rng(2024);
    const int n = 200000;
    std::vector<double> u(n), z(n), c(n);
    for (int i = 0; i < n; ++i) {
        u[i] = rng.uniform();
        z[i] = rng.normal();
        c[i] = rng.cauchy(0.5, 0.1);
    }
    std::sort(u.begin(), u.end());
    std::sort(z.begin(), z.end());
    std::sort(c.begin(), c.end());
    REQUIRE(u.front() >= 0.0);
    REQUIRE(u.back() < 1.0);
    boost::math::normal_distribution<> normal;
    boost::math::cauchy_distribution<> cauchy(0.5, 0.1);
    // The sample p-quantile has standard error sqrt(p(1-p)/n) / pdf(q); allow five of them.
    auto margin = [n](const auto& dist, double p) {
        return 5.0 * std::sqrt(p * (1 - p) / n) / boost::math::pdf(dist, boost::math::quantile(dist, p));
    };
    for (double p : {0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99}) {
        CHECK(quantile(u, p) == Approx(p).margin(5.0 * std::sqrt(p * (1 - p) / n)));
        CHECK(quantile(z, p) == Approx(boost::math::quantile(normal, p)).margin(margin(normal, p)));
        CHECK(quantile(c, p) == Approx(boost::math::quantile(cauchy, p)).margin(margin(cauchy, p)));
    }
}

TEST_CASE("below(n) is uniform over 0..n-1", "[random]") {
    Rng rng(5);
    std::vector<int> counts(7, 0);
    const int n = 70000;
    for (int i = 0; i < n; ++i) ++counts[rng.below(7)];
    for (int k : counts) CHECK(std::abs(k - n / 7) < 400);  // ~4.3 sigma
}

#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "framework/statistics.hpp"

using namespace mhb::stats;

TEST_CASE("summary of a small sample", "[statistics]") {
    std::vector<double> v{4, 1, 3, 2, 10};
    const auto s = summarize(v);
    REQUIRE(s.n == 5);
    REQUIRE(s.mean == Approx(4.0));
    REQUIRE(s.median == Approx(3.0));
    REQUIRE(s.min == 1);
    REQUIRE(s.max == 10);
    REQUIRE(s.sd == Approx(std::sqrt(50.0 / 4.0)));  // squares of deviations: 0+9+1+4+36
    REQUIRE(quantile({1, 2, 3, 4}, 0.25) == Approx(1.75));
}

TEST_CASE("average ranks give ties their mean rank", "[statistics]") {
    std::vector<double> v{10, 20, 20, 5};
    REQUIRE(average_ranks(v) == std::vector<double>{2, 3.5, 3.5, 1});
}

TEST_CASE("rank-sum test: exact p-values", "[statistics]") {
    // Complete separation of 3 vs 3: 2 of the C(6,3) = 20 arrangements are as extreme.
    std::vector<double> a{1, 2, 3}, b{4, 5, 6};
    auto r = wilcoxon_rank_sum(a, b);
    REQUIRE(r.exact);
    REQUIRE(r.u == 0);
    REQUIRE(r.p == Approx(0.1));
    // 5 vs 5 separated: 2 / C(10,5) = 2 / 252.
    std::vector<double> c{1, 2, 3, 4, 5}, d{6, 7, 8, 9, 10};
    REQUIRE(wilcoxon_rank_sum(c, d).p == Approx(2.0 / 252.0));
    // Hollander & Wolfe (1973, p. 69) permeability data, as in R's wilcox.test example: W = 35,
    // one-sided exact p = 0.1272, so two-sided 0.2544.
    std::vector<double> x{0.80, 0.83, 1.89, 1.04, 1.45, 1.38, 1.91, 1.64, 0.73, 1.46};
    std::vector<double> y{1.15, 0.88, 0.90, 0.74, 1.21};
    r = wilcoxon_rank_sum(x, y);
    REQUIRE(r.u == 35);
    REQUIRE(r.p == Approx(0.2544).margin(1e-4));
}

TEST_CASE("rank-sum test: normal approximation with ties", "[statistics]") {
    // a = {1,2,2}, b = {2,3,4}: ranks 1, 3, 3 | 3, 5, 6 -> U = 1; tie group of 3 gives
    // var = 9/12 * (7 - 24/30) = 4.65; z = (3.5 - 0.5)/sqrt(4.65) = 1.39122; p = 0.16417.
    std::vector<double> a{1, 2, 2}, b{2, 3, 4};
    const auto r = wilcoxon_rank_sum(a, b);
    REQUIRE_FALSE(r.exact);
    REQUIRE(r.u == 1);
    REQUIRE(std::abs(r.z) == Approx(1.39122).margin(1e-4));
    REQUIRE(r.p == Approx(0.16417).margin(1e-4));
    std::vector<double> same{1, 1, 1};
    REQUIRE(wilcoxon_rank_sum(same, same).p == 1.0);
}

TEST_CASE("Holm's adjustment, worked by hand and as R's p.adjust gives it", "[statistics]") {
    // Sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1: 0.02, 0.03, 0.06, 0.04 -> running maximum 0.06.
    const std::vector<double> p{0.01, 0.04, 0.03, 0.005};
    const auto adjusted = holm_adjusted(p);
    REQUIRE(adjusted.size() == 4);
    CHECK(adjusted[0] == Approx(0.03));
    CHECK(adjusted[1] == Approx(0.06));
    CHECK(adjusted[2] == Approx(0.06));
    CHECK(adjusted[3] == Approx(0.02));
    // Capped at 1: p.adjust(c(0.5, 0.6), "holm") = 1, 1.
    const std::vector<double> large{0.5, 0.6};
    CHECK(holm_adjusted(large) == std::vector<double>{1.0, 1.0});
    CHECK(holm_adjusted(std::vector<double>{}).empty());
}

TEST_CASE("Vargha-Delaney A12", "[statistics]") {
    std::vector<double> a{1, 2}, b{2, 3};
    REQUIRE(vargha_delaney_a12(a, b) == Approx(0.875));  // 1<2, 1<3, 2=2 (1/2), 2<3
    REQUIRE(vargha_delaney_a12(b, a) == Approx(0.125));
    REQUIRE(std::string(a12_magnitude(0.875)) == "large");
    REQUIRE(std::string(a12_magnitude(0.52)) == "negligible");
}

TEST_CASE("Friedman test on a consistent ranking", "[statistics]") {
    // Three problems, the same order each time: mean ranks 1, 2, 3; chi2 = 12*3/(3*4) * 2 = 6 and
    // with 2 degrees of freedom p = exp(-3).
    std::vector<std::vector<double>> scores{{0.1, 0.5, 0.9}, {1, 2, 3}, {-5, 0, 7}};
    const auto f = friedman(scores);
    REQUIRE(f.mean_ranks == std::vector<double>{1, 2, 3});
    REQUIRE(f.chi_square == Approx(6.0));
    REQUIRE(f.p == Approx(std::exp(-3.0)));
}

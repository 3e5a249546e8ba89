// ISOA's first strategy in isolation: the Tent map (eq. 13), the Tent population (eq. 14), the
// quasi-opposite points (eq. 15-16) and the selection of the best N of the union.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "optimizers/snake/tent_quasi_opposition.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

namespace {

Bounds uneven_box() {
    Bounds b;
    b.lower = (Vector(4) << -1.0, 0.0, 10.0, -100.0).finished();
    b.upper = (Vector(4) << 1.0, 5.0, 30.0, -99.0).finished();
    return b;
}

// A sphere that records every value it hands out (single-threaded tests only).
class RecordingSphere final : public Problem {
public:
    RecordingSphere(int dimension, double lower, double upper) { set_domain(dimension, lower, upper); }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        f = x.array().square().colwise().sum().transpose();
        for (Eigen::Index i = 0; i < f.size(); ++i) seen.push_back(f[i]);
    }
    mutable std::vector<double> seen;
};

}  // namespace

TEST_CASE("the Tent map follows eq. (13)", "[tent_quasi_opposition]") {
    REQUIRE(TentMap::step(0.3, 0.6) == Approx(0.5));
    REQUIRE(TentMap::step(0.6, 0.6) == 1.0);  // z = eps takes the first branch
    REQUIRE(TentMap::step(0.8, 0.6) == Approx(0.5));
    REQUIRE(TentMap::step(1.0, 0.6) == 0.0);
}

TEST_CASE("a Tent orbit stays in (0, 1)", "[tent_quasi_opposition]") {
    Rng rng(1);
    TentMap tent(0.6);
    for (int orbit = 0; orbit < 20; ++orbit) {
        tent.start(rng.uniform_open(), rng);
        for (int k = 0; k < 20000; ++k) {
            const double z = tent.next(rng);
            REQUIRE(z > 0.0);
            REQUIRE(z < 1.0);
        }
    }
}

TEST_CASE("a Tent orbit that leaves (0, 1) or repeats is re-seeded", "[tent_quasi_opposition]") {
    Rng rng(2);
    TentMap tent(0.6);
    tent.start(0.6, rng);  // 0.6 -> 1.0, which leaves (0, 1)
    REQUIRE(tent.reseeds() == 0);
    const double z = tent.next(rng);
    REQUIRE(tent.reseeds() == 1);
    REQUIRE(z > 0.0);
    REQUIRE(z < 1.0);
    tent.start(0.0, rng);  // not a valid start
    REQUIRE(tent.reseeds() == 2);

    // With eps = 0.001 the right branch has slope -1/0.999 and double rounding makes exact 2-cycles;
    // this pair was found by search: a -> b -> a.
    const double a = 0.50025012506252564, b = 0.50025012506253685;
    REQUIRE(TentMap::step(a, 0.001) == b);
    REQUIRE(TentMap::step(b, 0.001) == a);
    TentMap cycling(0.001);
    cycling.start(a, rng);
    REQUIRE(cycling.next(rng) == b);
    REQUIRE(cycling.reseeds() == 0);
    const double after = cycling.next(rng);
    REQUIRE(cycling.reseeds() == 1);
    REQUIRE(after != a);
}

TEST_CASE("the Tent population runs one orbit per coordinate along the individuals", "[tent_quasi_opposition]") {
    const Bounds box = uneven_box();
    TentQuasiOppositionInit init({0.6, 0.3});
    Rng rng(3);
    Matrix x(4, 200);
    init.tent_population(box, rng, x);
    REQUIRE(init.tent_reseeds() == 0);
    for (Eigen::Index j = 0; j < 4; ++j) {
        const double width = box.upper[j] - box.lower[j];
        for (Eigen::Index i = 0; i + 1 < x.cols(); ++i) {
            const double z = (x(j, i) - box.lower[j]) / width;
            const double z_next = (x(j, i + 1) - box.lower[j]) / width;
            // Recovering z from x loses a few ulps of the width; the map amplifies them by <= 2.5.
            REQUIRE(z_next == Approx(TentMap::step(z, 0.6)).margin(1e-11 * std::max(1.0, 1.0 / width)));
        }
    }
}

TEST_CASE("Tent points are uniform on the box (the skew tent map preserves Lebesgue measure)",
          "[tent_quasi_opposition]") {
    testing::ShiftedSphere unit(50, 0.0, 1.0, 0.0);
    TentQuasiOppositionInit init({0.6, 0.3});
    Rng rng(4);
    Matrix x(50, 2000);
    init.tent_population(unit.bounds(), rng, x);
    const double n = static_cast<double>(x.size());
    for (double q : {0.1, 0.25, 0.5, 0.75, 0.9}) {
        const double below = static_cast<double>((x.array() < q).count()) / n;
        // 100000 values: an independent sample would have sd <= 0.0016; the orbits are mixing but
        // correlated at short lags, so allow 0.01.
        REQUIRE(below == Approx(q).margin(0.01));
    }
}

TEST_CASE("quasi-opposite points lie between the centre and the opposite point, uniformly",
          "[tent_quasi_opposition]") {
    const Bounds box = uneven_box();
    Rng rng(5);
    std::vector<double> fractions;
    Vector x(4), qo(4);
    for (int k = 0; k < 20000; ++k) {
        for (Eigen::Index j = 0; j < 4; ++j) x[j] = rng.uniform(box.lower[j], box.upper[j]);
        quasi_opposite(x, box, rng, qo);
        for (Eigen::Index j = 0; j < 4; ++j) {
            const double centre = 0.5 * (box.lower[j] + box.upper[j]);
            const double opposite = box.lower[j] + box.upper[j] - x[j];
            REQUIRE(qo[j] >= std::min(centre, opposite) - 1e-12);
            REQUIRE(qo[j] <= std::max(centre, opposite) + 1e-12);
            if (std::abs(opposite - centre) > 1e-3 * (box.upper[j] - box.lower[j]))
                fractions.push_back((qo[j] - centre) / (opposite - centre));
        }
    }
    const double n = static_cast<double>(fractions.size());
    for (double q : {0.1, 0.5, 0.9}) {
        const double below = static_cast<double>(std::count_if(fractions.begin(), fractions.end(),
                                                                [q](double t) { return t < q; })) / n;
        REQUIRE(below == Approx(q).margin(5.0 * std::sqrt(q * (1 - q) / n)));
    }
}

TEST_CASE("each individual jumps to a quasi-opposite point with probability p", "[tent_quasi_opposition]") {
    const Bounds box = uneven_box();
    TentQuasiOppositionInit init({0.6, 0.3});
    Rng rng(6);
    const Eigen::Index n = 10000;
    Matrix x(4, n), out(4, n);
    std::vector<Eigen::Index> source(static_cast<std::size_t>(n));
    init.tent_population(box, rng, x);
    const Eigen::Index m = init.quasi_opposite_points(x, box, rng, out, source);
    // Binomial(10000, 0.3): mean 3000, sd 45.8.
    REQUIRE(std::abs(static_cast<double>(m) - 3000.0) < 5 * 45.8);
    for (Eigen::Index k = 0; k < m; ++k) {
        const auto i = source[static_cast<std::size_t>(k)];
        if (k > 0) REQUIRE(i > source[static_cast<std::size_t>(k - 1)]);
        for (Eigen::Index j = 0; j < 4; ++j) {
            const double centre = 0.5 * (box.lower[j] + box.upper[j]);
            const double opposite = box.lower[j] + box.upper[j] - x(j, i);
            REQUIRE(out(j, k) >= std::min(centre, opposite) - 1e-12);
            REQUIRE(out(j, k) <= std::max(centre, opposite) + 1e-12);
        }
    }
}

TEST_CASE("initialisation keeps the best N of the union and counts every evaluation", "[tent_quasi_opposition]") {
    RecordingSphere sphere(5, -3.0, 7.0);
    for (std::uint64_t seed = 1; seed <= 5; ++seed) {
        sphere.seen.clear();
        TentQuasiOppositionInit init({0.6, 0.3});
        const Eigen::Index n = 30;
        init.resize(5, n);
        Evaluator evaluator(sphere, Budget{10, 0});
        Rng rng(seed);
        Matrix population(5, n);
        Vector fitness(n);
        const auto spent = init.initialize(evaluator, rng, population, fitness);
        REQUIRE(spent == evaluator.evaluations());
        REQUIRE(spent == static_cast<std::int64_t>(sphere.seen.size()));
        REQUIRE(spent >= n);
        REQUIRE(spent <= 2 * n);
        std::vector<double> best = sphere.seen, kept(fitness.begin(), fitness.end());
        std::sort(best.begin(), best.end());
        best.resize(static_cast<std::size_t>(n));
        std::sort(kept.begin(), kept.end());
        REQUIRE(kept == best);
        for (Eigen::Index i = 0; i < n; ++i) REQUIRE(fitness[i] == population.col(i).squaredNorm());
    }
}

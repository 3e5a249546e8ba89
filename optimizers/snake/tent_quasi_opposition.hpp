#pragma once
// ISOA's first strategy (seed paper section 3.1.1, eq. 13-16): an initial population from Tent-map
// chaos, enlarged by quasi-opposite points, of which the best N are kept.
#include <array>
#include <cstdint>
#include <vector>

#include "framework/optimizer.hpp"

namespace mhb {

// The Tent map of eq. (13): z' = z/eps for z <= eps, (1 - z)/(1 - eps) otherwise. In floating point
// an orbit can land on 1 (from z = eps) and then on 0, or fall into a short cycle; `next` then
// re-seeds it with a fresh uniform draw, so every value it returns lies in (0, 1).
class TentMap {
public:
    // Short cycles are detected by comparing each new value with the last kMemory values.
    static constexpr int kMemory = 8;

    explicit TentMap(double epsilon);

    static double step(double z, double epsilon) { return z <= epsilon ? z / epsilon : (1.0 - z) / (1.0 - epsilon); }

    // Starts the orbit at `z`, or at a fresh uniform draw when z is not in (0, 1).
    void start(double z, Rng& rng);
    // Advances the orbit and returns the new value, re-seeding when the map leaves (0, 1) or repeats.
    double next(Rng& rng);
    double value() const { return z_; }
    std::int64_t reseeds() const { return reseeds_; }

private:
    void remember(double z);
    bool seen(double z) const;
    void reseed(Rng& rng);

    double epsilon_;
    double z_ = 0.5;
    std::array<double, kMemory> recent_{};
    int recent_count_ = 0;
    int recent_next_ = 0;
    std::int64_t reseeds_ = 0;
};

// Eq. (15) per coordinate: a point uniformly distributed between the centre of the box and the
// opposite point lb + ub - x, with a fresh uniform draw per coordinate.
void quasi_opposite(const Eigen::Ref<const Vector>& x, const Bounds& bounds, Rng& rng, Eigen::Ref<Vector> out);

struct TentQuasiOppositionSettings {
    double epsilon = 0.6;       // eq. (13)
    double jumping_rate = 0.3;  // p_i of eq. (16): probability that an individual gets a quasi-opposite point
};

class TentQuasiOppositionInit {
public:
    explicit TentQuasiOppositionInit(TentQuasiOppositionSettings settings);

    // Preallocates for `size` individuals of dimension `dimension`.
    void resize(Eigen::Index dimension, Eigen::Index size);

    // Eq. (14): individual i, coordinate j at lb_j + z_ij (ub_j - lb_j), where for each coordinate j
    // the orbit z_1j, z_2j, ... runs along the individuals from a uniform random start.
    void tent_population(const Bounds& bounds, Rng& rng, Eigen::Ref<Matrix> out);

    // Eq. (16): with probability jumping_rate, individual i contributes a quasi-opposite point.
    // Writes them to the first columns of `out` and their source individuals to `source`; returns
    // how many there are.
    Eigen::Index quasi_opposite_points(const Eigen::Ref<const Matrix>& population, const Bounds& bounds, Rng& rng,
                                       Eigen::Ref<Matrix> out, std::vector<Eigen::Index>& source);

    // The whole strategy: tent population (evaluated), quasi-opposite points (evaluated), and the
    // best `population.cols()` of the union written to population/fitness in union order. Spends
    // N + (number of quasi-opposite points) evaluations; returns that number.
    std::int64_t initialize(Evaluator& evaluator, Rng& rng, Eigen::Ref<Matrix> population, Eigen::Ref<Vector> fitness);

    std::int64_t tent_reseeds() const { return tent_.reseeds(); }

private:
    TentQuasiOppositionSettings settings_;
    TentMap tent_;
    Matrix union_;                       // D x 2N: the tent points, then the quasi-opposite points
    Vector union_fitness_;
    std::vector<Eigen::Index> source_;
    std::vector<Eigen::Index> order_;
};

}  // namespace mhb

// Particle swarm optimisation with inertia weight (Shi & Eberhart 1998), global-best topology,
// inertia decreasing linearly from w_max to w_min over the run. The swarm moves synchronously: all
// particles move, the swarm is evaluated in one call, then personal and global bests are updated.
// Choices (velocity limit, walls, initial velocities) are documented in docs/baselines.md.
#include <algorithm>
#include <limits>

#include "framework/registry.hpp"

namespace mhb {
namespace {

class ParticleSwarm final : public Optimizer {
public:
    explicit ParticleSwarm(const ParameterSet& p)
        : population_(static_cast<Eigen::Index>(p.integer("population"))),
          w_max_(p.real("w_max")),
          w_min_(p.real("w_min")),
          c1_(p.real("c1")),
          c2_(p.real("c2")),
          vmax_fraction_(p.real("vmax_fraction")),
          stop_at_wall_(p.boolean("stop_at_wall")) {}

    void initialize(Evaluator& evaluator, Rng& rng) override {
        const int dim = evaluator.dimension();
        const Bounds& b = evaluator.bounds();
        vmax_ = vmax_fraction_ * (b.upper - b.lower);
        positions_.resize(dim, population_);
        // Particles start at rest: random initial velocities throw many particles onto the walls in
        // the first step (Engelbrecht 2012), and the social term alone sets the swarm moving.
        velocities_.setZero(dim, population_);
        fitness_.resize(population_);
        fill_uniform(positions_, b, rng);
        evaluator.evaluate(positions_, fitness_);
        personal_best_ = positions_;
        personal_best_fitness_ = fitness_;
        // A swarm whose every fitness is +inf still needs a global best for the velocity formula.
        global_best_ = positions_.col(0);
        global_best_fitness_ = std::numeric_limits<double>::infinity();
        update_global_best();
    }

    void iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) override {
        // w = w_max - (w_max - w_min) t / T with t = 1..T, so the last iteration runs with w_min.
        const double w = w_max_ - (w_max_ - w_min_) * progress.fraction(0);
        const Bounds& b = evaluator.bounds();
        for (Eigen::Index i = 0; i < population_; ++i) {
            for (Eigen::Index j = 0; j < positions_.rows(); ++j) {
                const double x = positions_(j, i);
                double v = w * velocities_(j, i) + c1_ * rng.uniform() * (personal_best_(j, i) - x) +
                           c2_ * rng.uniform() * (global_best_[j] - x);
                v = std::clamp(v, -vmax_[j], vmax_[j]);
                double moved = x + v;
                if (moved < b.lower[j] || moved > b.upper[j]) {
                    moved = std::clamp(moved, b.lower[j], b.upper[j]);
                    if (stop_at_wall_) v = 0.0;
                }
                positions_(j, i) = moved;
                velocities_(j, i) = v;
            }
        }
        evaluator.evaluate(positions_, fitness_);
        for (Eigen::Index i = 0; i < population_; ++i) {
            if (fitness_[i] < personal_best_fitness_[i]) {
                personal_best_fitness_[i] = fitness_[i];
                personal_best_.col(i) = positions_.col(i);
            }
        }
        update_global_best();
    }

private:
    void update_global_best() {
        Eigen::Index best = 0;
        const double f = personal_best_fitness_.minCoeff(&best);
        if (f < global_best_fitness_) {
            global_best_fitness_ = f;
            global_best_ = personal_best_.col(best);
        }
    }

    Eigen::Index population_;
    double w_max_, w_min_, c1_, c2_, vmax_fraction_;
    bool stop_at_wall_;
    Vector vmax_;
    Matrix positions_;
    Matrix velocities_;
    Vector fitness_;
    Matrix personal_best_;
    Vector personal_best_fitness_;
    Vector global_best_;
    double global_best_fitness_ = std::numeric_limits<double>::infinity();
};

const bool registered = register_optimizer({
    "pso",
    "Particle swarm with linearly decreasing inertia weight (Shi & Eberhart 1998)",
    {
        ParameterSpec::integer("population", 30, 1, 1'000'000, "number of particles"),
        ParameterSpec::real("w_max", 0.9, 0.0, 2.0, "inertia weight at the start of the run"),
        ParameterSpec::real("w_min", 0.4, 0.0, 2.0, "inertia weight at the end of the run"),
        ParameterSpec::real("c1", 2.0, 0.0, 4.0, "cognitive acceleration (pull towards the particle's own best)"),
        ParameterSpec::real("c2", 2.0, 0.0, 4.0, "social acceleration (pull towards the swarm's best)"),
        ParameterSpec::real("vmax_fraction", 0.2, 1e-6, 10.0,
                            "velocity limit per coordinate as a fraction of that coordinate's range"),
        ParameterSpec::boolean("stop_at_wall", true,
                               "a particle clamped onto a bound loses that velocity component (else it keeps it)"),
    },
    [](const ParameterSet& p) { return std::make_unique<ParticleSwarm>(p); },
});

}  // namespace
}  // namespace mhb

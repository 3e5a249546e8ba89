// Differential evolution, DE/rand/1/bin (Storn & Price 1997, J. Global Optimization 11:341-359).
// Generational: the whole trial population is built from the current one, evaluated in one call,
// then each trial competes one-to-one with its parent. Choices are documented in docs/baselines.md.
#include "optimizers/differential_evolution.hpp"

#include <algorithm>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"

namespace mhb::de {

Donors draw_donors(Eigen::Index target, Eigen::Index population, Rng& rng) {
    // Rejection keeps every ordered triple of distinct non-target indices equally likely.
    const auto n = static_cast<std::uint64_t>(population);
    Donors d;
    do d.r1 = static_cast<Eigen::Index>(rng.below(n));
    while (d.r1 == target);
    do d.r2 = static_cast<Eigen::Index>(rng.below(n));
    while (d.r2 == target || d.r2 == d.r1);
    do d.r3 = static_cast<Eigen::Index>(rng.below(n));
    while (d.r3 == target || d.r3 == d.r1 || d.r3 == d.r2);
    return d;
}

Donors make_trial(const Matrix& population, Eigen::Index target, double f, double cr, BoundRepair repair,
                  const Bounds& bounds, Rng& rng, Eigen::Ref<Vector> trial) {
    const Eigen::Index dim = population.rows();
    const Donors d = draw_donors(target, population.cols(), rng);
    const Eigen::Index j_rand = static_cast<Eigen::Index>(rng.below(static_cast<std::uint64_t>(dim)));
    for (Eigen::Index j = 0; j < dim; ++j) {
        const double parent = population(j, target);
        // One uniform per coordinate, drawn also for j_rand, so the stream does not depend on j_rand.
        const bool from_mutant = rng.uniform() < cr || j == j_rand;
        if (!from_mutant) {
            trial[j] = parent;
            continue;
        }
        double v = population(j, d.r1) + f * (population(j, d.r2) - population(j, d.r3));
        const double lo = bounds.lower[j], hi = bounds.upper[j];
        if (v < lo || v > hi) {
            if (repair == BoundRepair::Clamp) v = v < lo ? lo : hi;
            else v = v < lo ? lo + rng.uniform() * (parent - lo) : hi - rng.uniform() * (hi - parent);
            // Rounding in the redraw must not step outside the box the evaluator enforces.
            v = std::clamp(v, lo, hi);
        }
        trial[j] = v;
    }
    return d;
}

namespace {

class DifferentialEvolution final : public Optimizer {
public:
    explicit DifferentialEvolution(const ParameterSet& p)
        : requested_population_(p.integer("population")),
          f_(p.real("F")),
          cr_(p.real("CR")),
          repair_(p.text("boundary") == "clamp" ? BoundRepair::Clamp : BoundRepair::BetweenParentAndBound) {
        if (requested_population_ != 0 && requested_population_ < 4)
            throw ParameterError("population", "must be 0 (meaning 10 x dimension) or at least 4, since r1, r2, r3 "
                                               "and the target must differ (got " +
                                                   std::to_string(requested_population_) + ")");
    }

    void initialize(Evaluator& evaluator, Rng& rng) override {
        const int dim = evaluator.dimension();
        const Eigen::Index np = requested_population_ == 0 ? 10 * static_cast<Eigen::Index>(dim)
                                                           : static_cast<Eigen::Index>(requested_population_);
        population_.resize(dim, np);
        trials_.resize(dim, np);
        fitness_.resize(np);
        trial_fitness_.resize(np);
        fill_uniform(population_, evaluator.bounds(), rng);
        evaluator.evaluate(population_, fitness_);
    }

    void iterate(const Progress&, Evaluator& evaluator, Rng& rng) override {
        const Bounds& bounds = evaluator.bounds();
        for (Eigen::Index i = 0; i < population_.cols(); ++i)
            make_trial(population_, i, f_, cr_, repair_, bounds, rng, trials_.col(i));
        evaluator.evaluate(trials_, trial_fitness_);
        // Storn & Price keep the trial when it is not worse, which lets the population move across
        // plateaus. Trials past the budget have +inf and never replace an evaluated parent.
        for (Eigen::Index i = 0; i < population_.cols(); ++i) {
            if (trial_fitness_[i] <= fitness_[i]) {
                population_.col(i) = trials_.col(i);
                fitness_[i] = trial_fitness_[i];
            }
        }
    }

private:
    std::int64_t requested_population_;
    double f_;
    double cr_;
    BoundRepair repair_;
    Matrix population_;
    Matrix trials_;
    Vector fitness_;
    Vector trial_fitness_;
};

const bool registered = register_optimizer({
    "de",
    "Differential evolution DE/rand/1/bin (Storn & Price 1997)",
    {
        ParameterSpec::integer("population", 50, 0, 1'000'000,
                               "population size NP; 0 = 10 x dimension (Storn & Price's rule of thumb); else >= 4"),
        ParameterSpec::real("F", 0.5, 0.0, 2.0, "differential weight F in v = x_r1 + F (x_r2 - x_r3)"),
        ParameterSpec::real("CR", 0.9, 0.0, 1.0, "crossover rate: probability that a coordinate comes from the mutant"),
        ParameterSpec::choice("boundary", "between_parent_and_bound", {"between_parent_and_bound", "clamp"},
                              "repair of a mutant coordinate outside the box: redraw it uniformly between the "
                              "parent and the violated bound, or clamp it onto the bound"),
    },
    [](const ParameterSet& p) { return std::make_unique<DifferentialEvolution>(p); },
});

}  // namespace
}  // namespace mhb::de

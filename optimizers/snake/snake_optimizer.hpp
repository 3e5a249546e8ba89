#pragma once
// The Snake Optimizer (Hashim & Hussien 2022) as the authors' SO.m does it, with ISOA's three
// strategies (He et al. 2024) as independent components: Tent-chaos + quasi-opposition
// initialisation, other phase thresholds, and a Cauchy-mutated cuckoo search pass after SO's
// update. SOA, ISOA and the ablations between them are this one class with components on or off.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "framework/optimizer.hpp"
#include "optimizers/snake/cauchy_cuckoo_search.hpp"
#include "optimizers/snake/snake_phase_schedule.hpp"
#include "optimizers/snake/tent_quasi_opposition.hpp"

namespace mhb {

// How the ratios exp(-f_other / (f_self + eps)) of SO's equations are computed.
enum class FitnessRatio {
    Faithful,  // as SO.m, on the raw fitness: assumes f >= 0 and overflows on negative objectives
    Shifted,   // on f - (current population minimum), so that every ratio lies in [0, 1]
};

// Which best position a sex's cuckoo pass steps relative to (eq. 24's X_b).
enum class CuckooLeader { OwnSex, Food };

FitnessRatio parse_fitness_ratio(const std::string& name);
CuckooLeader parse_cuckoo_leader(const std::string& name);
CauchyAlphaRule parse_cauchy_alpha_rule(const std::string& name);

struct SnakeSettings {
    Eigen::Index population = 30;  // even: first half males, second half females
    SnakePhaseSchedule schedule;    // 0.25 / 0.6 (SO), 0.22 / 0.8 (ISOA)
    FitnessRatio fitness_ratio = FitnessRatio::Faithful;
    std::optional<TentQuasiOppositionSettings> tent_init;  // engaged: ISOA strategy 1
    std::optional<CauchyCuckooSettings> cuckoo;            // engaged: ISOA strategy 3
    CuckooLeader cuckoo_leader = CuckooLeader::OwnSex;
};

// The ratio exp(-(f_other - shift) / (f_self - shift + eps)) with eps = 2.2e-16 (MATLAB's eps).
double snake_fitness_ratio(double f_other, double f_self, double shift);

class SnakeOptimizer final : public Optimizer {
public:
    static constexpr double kC2 = 0.05;            // exploration step (SO.m)
    static constexpr double kC3 = 2.0;             // exploitation step (SO.m)
    static constexpr double kFightThreshold = 0.6; // one rand per cold iteration: > 0.6 fight, else mating

    // Throws ParameterError for an odd population, or fewer than 3 snakes per sex with the cuckoo pass.
    explicit SnakeOptimizer(SnakeSettings settings);

    void initialize(Evaluator& evaluator, Rng& rng) override;
    void iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) override;

    // Introspection for tests and diagnostics.
    SnakePhase last_phase() const { return phase_; }
    bool last_egg_hatched() const { return egg_hatched_; }
    // The last batch of candidates evaluated (after clamping), one column per snake: the SO update's,
    // or with the cuckoo pass on, the discovery pass's.
    const Matrix& last_candidates() const { return candidates_; }
    const Matrix& positions() const { return positions_; }
    const Vector& fitness() const { return fitness_; }
    const Vector& food() const { return food_; }
    double food_fitness() const { return food_fitness_; }
    // SO candidates that came out with a NaN coordinate and were rejected (faithful ratios only).
    std::int64_t rejected_non_finite() const { return rejected_non_finite_; }
    std::int64_t initial_evaluations() const { return initial_evaluations_; }
    // The cuckoo location mu of males (sex 0) and females (sex 1).
    double cuckoo_mu(int sex) const;

private:
    struct Sex {
        Eigen::Index first = 0;  // first column of this sex
        Vector best;             // best-so-far position (SO.m's Xbest_m / Xbest_f)
        double best_fitness = 0.0;
    };

    double ratio(double f_other, double f_self) const { return snake_fitness_ratio(f_other, f_self, shift_); }
    void explore(const Sex& sex, const Bounds& bounds, Rng& rng);
    void hot(const Sex& sex, double temperature, Rng& rng);
    void fight(const Sex& sex, const Sex& other, double q, Rng& rng);
    void mate(const Sex& sex, const Sex& other, double q, Rng& rng);
    void hatch(const Sex& sex, const Bounds& bounds, Rng& rng);
    // A NaN coordinate (faithful ratios: inf * 0) cannot be evaluated; the candidate is replaced
    // by its parent and its fitness forced to +inf after evaluation, which is what SO.m's
    // `if y < fitness` does with a NaN y.
    void guard_non_finite();
    void update_best(Sex& sex);
    void refresh_food();
    void cuckoo_pass(Evaluator& evaluator, Rng& rng);

    SnakeSettings settings_;
    Eigen::Index half_;
    Matrix positions_;
    Vector fitness_;
    Matrix candidates_;
    Vector candidate_fitness_;
    std::vector<char> rejected_;
    Sex male_, female_;
    Vector food_;
    double food_fitness_ = 0.0;
    double shift_ = 0.0;
    std::optional<TentQuasiOppositionInit> tent_init_;
    std::optional<CauchyCuckooSearch> male_cuckoo_, female_cuckoo_;
    SnakePhase phase_ = SnakePhase::Exploration;
    bool egg_hatched_ = false;
    std::int64_t rejected_non_finite_ = 0;
    std::int64_t initial_evaluations_ = 0;
};

}  // namespace mhb

#include "optimizers/snake/snake_optimizer.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "optimizers/greedy_selection.hpp"

namespace mhb {

FitnessRatio parse_fitness_ratio(const std::string& name) {
    if (name == "faithful") return FitnessRatio::Faithful;
    if (name == "shifted") return FitnessRatio::Shifted;
    throw ParameterError("fitness_ratio", "expects faithful or shifted (got " + name + ")");
}

CuckooLeader parse_cuckoo_leader(const std::string& name) {
    if (name == "own_sex") return CuckooLeader::OwnSex;
    if (name == "food") return CuckooLeader::Food;
    throw ParameterError("cuckoo_leader", "expects own_sex or food (got " + name + ")");
}

CauchyAlphaRule parse_cauchy_alpha_rule(const std::string& name) {
    if (name == "jade") return CauchyAlphaRule::Jade;
    if (name == "raw") return CauchyAlphaRule::Raw;
    throw ParameterError("cauchy_alpha", "expects jade or raw (got " + name + ")");
}

double snake_fitness_ratio(double f_other, double f_self, double shift) {
    constexpr double kEps = 2.220446049250313e-16;
    return std::exp(-(f_other - shift) / (f_self - shift + kEps));
}

SnakeOptimizer::SnakeOptimizer(SnakeSettings settings) : settings_(settings), half_(settings.population / 2) {
    if (settings_.population < 2 || settings_.population % 2 != 0)
        throw ParameterError("population",
                             fmt::format("the Snake Optimizer splits the population into two equal halves (males "
                                         "and females), so it must be even and at least 2 (got {})",
                                         settings_.population));
    if (settings_.cuckoo && half_ < 3)
        throw ParameterError("population",
                             fmt::format("the cuckoo pass picks two other snakes of the same sex, so each sex needs "
                                         "at least 3 (population >= 6; got {})",
                                         settings_.population));
    if (settings_.tent_init) tent_init_.emplace(*settings_.tent_init);
    if (settings_.cuckoo) {
        male_cuckoo_.emplace(*settings_.cuckoo);
        female_cuckoo_.emplace(*settings_.cuckoo);
    }
}

double SnakeOptimizer::cuckoo_mu(int sex) const {
    if (!male_cuckoo_) return std::numeric_limits<double>::quiet_NaN();
    return sex == 0 ? male_cuckoo_->mu() : female_cuckoo_->mu();
}

void SnakeOptimizer::initialize(Evaluator& evaluator, Rng& rng) {
    const Eigen::Index d = evaluator.dimension();
    const Eigen::Index n = settings_.population;
    positions_.resize(d, n);
    fitness_.resize(n);
    candidates_.resize(d, n);
    candidate_fitness_.resize(n);
    rejected_.assign(static_cast<std::size_t>(n), 0);
    male_.first = 0;
    female_.first = half_;
    rejected_non_finite_ = 0;
    phase_ = SnakePhase::Exploration;
    egg_hatched_ = false;

    const std::int64_t before = evaluator.evaluations();
    if (tent_init_) {
        tent_init_->resize(d, n);
        tent_init_->initialize(evaluator, rng, positions_, fitness_);
    } else {
        fill_uniform(positions_, evaluator.bounds(), rng);
        evaluator.evaluate(positions_, fitness_);
    }
    initial_evaluations_ = evaluator.evaluations() - before;

    for (Sex* sex : {&male_, &female_}) {
        const Eigen::Index k = sex->first + index_of_best(fitness_.segment(sex->first, half_));
        sex->best = positions_.col(k);
        sex->best_fitness = fitness_[k];
    }
    const Eigen::Index k = index_of_best(fitness_);
    food_ = positions_.col(k);
    food_fitness_ = fitness_[k];

    if (male_cuckoo_) {
        male_cuckoo_->resize(d, half_);
        female_cuckoo_->resize(d, half_);
    }
}

void SnakeOptimizer::iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) {
    const Bounds& bounds = evaluator.bounds();
    const double fraction = progress.fraction(0);
    const double q = SnakePhaseSchedule::food_quantity(fraction);
    shift_ = settings_.fitness_ratio == FitnessRatio::Shifted ? fitness_.minCoeff() : 0.0;
    egg_hatched_ = false;

    if (settings_.schedule.exploring(fraction)) {
        phase_ = SnakePhase::Exploration;
        explore(male_, bounds, rng);
        explore(female_, bounds, rng);
    } else if (settings_.schedule.hot(fraction)) {
        phase_ = SnakePhase::Hot;
        const double temperature = SnakePhaseSchedule::temperature(fraction);
        hot(male_, temperature, rng);
        hot(female_, temperature, rng);
    } else if (rng.uniform() > kFightThreshold) {
        phase_ = SnakePhase::Fight;
        fight(male_, female_, q, rng);
        fight(female_, male_, q, rng);
    } else {
        phase_ = SnakePhase::Mating;
        mate(male_, female_, q, rng);
        mate(female_, male_, q, rng);
        if (rng.uniform() < 0.5) {
            egg_hatched_ = true;
            hatch(male_, bounds, rng);
            hatch(female_, bounds, rng);
        }
    }

    guard_non_finite();
    clamp_to_bounds(candidates_, bounds);
    evaluator.evaluate(candidates_, candidate_fitness_);
    for (Eigen::Index i = 0; i < candidate_fitness_.size(); ++i)
        if (rejected_[static_cast<std::size_t>(i)]) candidate_fitness_[i] = std::numeric_limits<double>::infinity();
    greedy_replace(positions_, fitness_, candidates_, candidate_fitness_);
    update_best(male_);
    update_best(female_);

    if (male_cuckoo_) cuckoo_pass(evaluator, rng);
    refresh_food();
}

void SnakeOptimizer::explore(const Sex& sex, const Bounds& bounds, Rng& rng) {
    const auto half = static_cast<std::uint64_t>(half_);
    for (Eigen::Index i = sex.first; i < sex.first + half_; ++i) {
        for (Eigen::Index j = 0; j < positions_.rows(); ++j) {
            const Eigen::Index r = sex.first + static_cast<Eigen::Index>(rng.below(half));
            const double sign = rng.sign();
            const double a = ratio(fitness_[r], fitness_[i]);
            const double lower = bounds.lower[j];
            candidates_(j, i) =
                positions_(j, r) + sign * kC2 * a * ((bounds.upper[j] - lower) * rng.uniform() + lower);
        }
    }
}

void SnakeOptimizer::hot(const Sex& sex, double temperature, Rng& rng) {
    for (Eigen::Index i = sex.first; i < sex.first + half_; ++i) {
        const double sign = rng.sign();
        for (Eigen::Index j = 0; j < positions_.rows(); ++j)
            candidates_(j, i) = food_[j] + kC3 * sign * temperature * rng.uniform() * (food_[j] - positions_(j, i));
    }
}

void SnakeOptimizer::fight(const Sex& sex, const Sex& other, double q, Rng& rng) {
    for (Eigen::Index i = sex.first; i < sex.first + half_; ++i) {
        const double f = ratio(other.best_fitness, fitness_[i]);
        for (Eigen::Index j = 0; j < positions_.rows(); ++j) {
            const double x = positions_(j, i);
            candidates_(j, i) = x + kC3 * f * rng.uniform() * (q * other.best[j] - x);
        }
    }
}

void SnakeOptimizer::mate(const Sex& sex, const Sex& other, double q, Rng& rng) {
    for (Eigen::Index k = 0; k < half_; ++k) {
        const Eigen::Index i = sex.first + k;
        const Eigen::Index partner = other.first + k;
        const double m = ratio(fitness_[partner], fitness_[i]);
        for (Eigen::Index j = 0; j < positions_.rows(); ++j) {
            const double x = positions_(j, i);
            candidates_(j, i) = x + kC3 * rng.uniform() * m * (q * positions_(j, partner) - x);
        }
    }
}

void SnakeOptimizer::hatch(const Sex& sex, const Bounds& bounds, Rng& rng) {
    const Eigen::Index worst = sex.first + index_of_worst(fitness_.segment(sex.first, half_));
    const double r = rng.uniform();
    candidates_.col(worst) = bounds.lower + r * (bounds.upper - bounds.lower);
}

void SnakeOptimizer::guard_non_finite() {
    for (Eigen::Index i = 0; i < candidates_.cols(); ++i) {
        const bool nan = candidates_.col(i).hasNaN();
        rejected_[static_cast<std::size_t>(i)] = nan;
        if (!nan) continue;
        candidates_.col(i) = positions_.col(i);
        ++rejected_non_finite_;
    }
}

void SnakeOptimizer::update_best(Sex& sex) {
    const Eigen::Index k = sex.first + index_of_best(fitness_.segment(sex.first, half_));
    if (fitness_[k] < sex.best_fitness) {
        sex.best = positions_.col(k);
        sex.best_fitness = fitness_[k];
    }
}

void SnakeOptimizer::refresh_food() {
    const Sex& better = male_.best_fitness < female_.best_fitness ? male_ : female_;
    food_ = better.best;
    food_fitness_ = better.best_fitness;
}

void SnakeOptimizer::cuckoo_pass(Evaluator& evaluator, Rng& rng) {
    const Bounds& bounds = evaluator.bounds();
    const Sex& global = male_.best_fitness < female_.best_fitness ? male_ : female_;
    auto males = [&](auto& m) { return m.middleCols(male_.first, half_); };
    auto females = [&](auto& m) { return m.middleCols(female_.first, half_); };
    const Vector& male_leader = settings_.cuckoo_leader == CuckooLeader::OwnSex ? male_.best : global.best;
    const Vector& female_leader = settings_.cuckoo_leader == CuckooLeader::OwnSex ? female_.best : global.best;

    male_cuckoo_->propose_levy(males(positions_), male_leader, bounds, rng, males(candidates_));
    female_cuckoo_->propose_levy(females(positions_), female_leader, bounds, rng, females(candidates_));
    evaluator.evaluate(candidates_, candidate_fitness_);
    male_cuckoo_->accept_levy(males(positions_), fitness_.segment(male_.first, half_), males(candidates_),
                              candidate_fitness_.segment(male_.first, half_));
    female_cuckoo_->accept_levy(females(positions_), fitness_.segment(female_.first, half_), females(candidates_),
                                candidate_fitness_.segment(female_.first, half_));
    update_best(male_);
    update_best(female_);

    male_cuckoo_->propose_discovery(males(positions_), bounds, rng, males(candidates_));
    female_cuckoo_->propose_discovery(females(positions_), bounds, rng, females(candidates_));
    evaluator.evaluate(candidates_, candidate_fitness_);
    greedy_replace(positions_, fitness_, candidates_, candidate_fitness_);
    update_best(male_);
    update_best(female_);
}

}  // namespace mhb

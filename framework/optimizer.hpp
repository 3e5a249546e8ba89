#pragma once
// The optimiser interface: step-wise (initialise, then iterate), with the random generator and the
// evaluation counter injected by the framework. An optimiser never calls a problem directly; it asks
// the Evaluator, which counts every evaluation, enforces the budget and checks the plugin's output.
#include <cstdint>
#include <limits>

#include "framework/problem.hpp"
#include "framework/random.hpp"

namespace mhb {

// A run ends when either limit is reached (0 = no limit; at least one must be set).
struct Budget {
    std::int64_t max_iterations = 0;
    std::int64_t max_evaluations = 0;
};

class AnytimeRecorder;

class Evaluator {
public:
    Evaluator(const Problem& problem, Budget budget);

    // Evaluates the columns of `x` into `f`. Columns past the remaining budget are not evaluated and
    // get +inf, so greedy selection rejects them. Throws PluginFault on a candidate that is not
    // finite or leaves the box, or on a NaN fitness. Returns how many columns were evaluated.
    Eigen::Index evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f);

    bool exhausted() const { return budget_.max_evaluations > 0 && used_ >= budget_.max_evaluations; }
    std::int64_t evaluations() const { return used_; }
    // Evaluations still allowed (max int64 when only iterations are limited).
    std::int64_t remaining() const;
    const Budget& budget() const { return budget_; }

    const Problem& problem() const { return problem_; }
    const Bounds& bounds() const { return problem_.bounds(); }
    int dimension() const { return problem_.dimension(); }

    // Best point evaluated so far (the framework's own record, not the optimiser's claim).
    double best_fitness() const { return best_fitness_; }
    const Vector& best_position() const { return best_position_; }

    // Tells `recorder` (which must outlive the evaluator) the best-so-far after every evaluation.
    void record_anytime(AnytimeRecorder* recorder) { recorder_ = recorder; }

private:
    const Problem& problem_;
    Budget budget_;
    std::int64_t used_ = 0;
    double best_fitness_ = std::numeric_limits<double>::infinity();
    Vector best_position_;
    AnytimeRecorder* recorder_ = nullptr;
};

// Where a run stands when an iteration starts.
struct Progress {
    std::int64_t iteration = 1;  // 1-based index of the iteration about to run
    std::int64_t evaluations = 0;
    // Evaluations the previous step used (the initialisation, for iteration 1): how far one
    // iteration moves an evaluation budget.
    std::int64_t last_step_evaluations = 0;
    Budget budget;

    // Fraction of the run used, for schedules written as t/T: with an iteration budget
    // (iteration + offset) / T; with an evaluation budget (evaluations + offset * last step) / E, so
    // an offset means the same under both (the larger of the two when both are set); clamped to
    // [0, 1]. SO's t/T is fraction(0); GWO's l/T (l = 0..T-1) is fraction(-1).
    double fraction(std::int64_t offset = 0) const;
};

class Optimizer {
public:
    virtual ~Optimizer() = default;
    // Creates and evaluates the initial population.
    virtual void initialize(Evaluator& evaluator, Rng& rng) = 0;
    // One iteration (generation).
    virtual void iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) = 0;
};

// Clamps every coordinate of every column of `x` into the box.
void clamp_to_bounds(Eigen::Ref<Matrix> x, const Bounds& bounds);
// Fills `x` with uniform random points in the box.
void fill_uniform(Eigen::Ref<Matrix> x, const Bounds& bounds, Rng& rng);

}  // namespace mhb

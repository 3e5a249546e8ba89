#pragma once
// Anytime records, for runtime-to-target analysis as COCO and IOHprofiler do it: while a trial runs,
// the evaluator reports every evaluation to a recorder that keeps (1) the best-so-far f at
// log-spaced evaluation counts and (2) for each target precision (f - f*), the first evaluation that
// reached it. Both are exact to the evaluation, whatever population the optimiser evaluates at once.
#include <cstdint>
#include <string>
#include <vector>

namespace mhb {

// `[anytime]` of an experiment config (docs/config-reference.md).
struct AnytimeSpec {
    std::vector<double> targets;      // f - f* precisions, strictly decreasing, > 0
    std::vector<double> ert_targets;  // those of `targets` the ERT table shows
    int points_per_decade = 5;        // best-so-far checkpoints per decade of evaluations; 0: none
    int bootstrap = 1000;             // resamples for the confidence intervals
    // false: a trial keeps only its final state as its convergence trace (no entry per iteration),
    // which is most of a campaign's records; the anytime record replaces it.
    bool iteration_trace = true;
    // Checkpoints of the evaluation budget at which every trial records its best-so-far, as the CEC
    // competitions ask (`checkpoints` in the config). Either fractions of the budget, or, when
    // `checkpoints_rule` is "cec2022", the fractions D^e for e in `checkpoint_exponents`; empty: none.
    std::vector<double> checkpoints;
    std::string checkpoints_rule;               // the name the config gave ("cec2017", "cec2022") or empty
    std::vector<double> checkpoint_exponents;   // fraction = dimension^e (the CEC 2022 rule)
    bool operator==(const AnytimeSpec&) const = default;
};

// The evaluation counts at which a trial of this dimension and evaluation budget records its
// best-so-far: floor(fraction * budget), at least 1, increasing, without repeats. Empty without
// checkpoints or without an evaluation budget.
std::vector<std::int64_t> checkpoint_evaluations(const AnytimeSpec& spec, int dimension, std::int64_t max_evaluations);

// The named checkpoint rules of the CEC reports: "cec2017" (0.01, 0.02, 0.03, 0.05, 0.1, 0.2, ...,
// 1.0 of MaxFES; Awad et al. 2016, 2.2) and "cec2022" (D^(k/5 - 3) of MaxFES, k = 0..15; Kumar et
// al. 2021, 2.2). False for another name.
bool set_named_checkpoints(AnytimeSpec& spec, const std::string& name);

// COCO's default targets for runtime ECDFs: 10^2 down to 10^-8, five per decade (51 values).
std::vector<double> bbob_targets();

// What one trial recorded.
struct AnytimeRecord {
    std::vector<std::int64_t> evaluations;  // checkpoints reached (1, 2, 3, 4, 7, 10, 16, ... at 5 per decade)
    std::vector<double> best;               // best-so-far f after that many evaluations
    std::vector<std::int64_t> hits;         // per target: the first evaluation with f - f* <= target; 0: never
    std::vector<double> hit_best;           // per target: the best-so-far f at that evaluation (NaN: never)
    // The budget's checkpoints the trial reached (checkpoint_evaluations) and its best-so-far f there.
    std::vector<std::int64_t> checkpoint_evaluations;
    std::vector<double> checkpoint_best;
    bool empty() const { return evaluations.empty() && hits.empty() && checkpoint_evaluations.empty(); }
};

class AnytimeRecorder {
public:
    // `optimum`: the problem's f*. Targets are taken from `spec` (decreasing); `checkpoints` are the
    // evaluation counts of checkpoint_evaluations.
    AnytimeRecorder(const AnytimeSpec& spec, double optimum, std::vector<std::int64_t> checkpoints = {});

    // The best-so-far `best` after evaluation number `count` (1-based, each count once, in order).
    void observe(std::int64_t count, double best) {
        while (count >= next_checkpoint_) {
            if (count == next_checkpoint_) {
                record_.evaluations.push_back(count);
                record_.best.push_back(best);
            }
            advance_checkpoint();
        }
        while (next_budget_checkpoint_ < budget_checkpoints_.size() && count >= budget_checkpoints_[next_budget_checkpoint_]) {
            record_.checkpoint_evaluations.push_back(budget_checkpoints_[next_budget_checkpoint_]);
            record_.checkpoint_best.push_back(best);
            ++next_budget_checkpoint_;
        }
        while (next_target_ < targets_.size() && best - optimum_ <= targets_[next_target_]) {
            record_.hits[next_target_] = count;
            record_.hit_best[next_target_] = best;
            ++next_target_;
        }
    }

    AnytimeRecord take() { return std::move(record_); }

private:
    void advance_checkpoint();

    std::vector<double> targets_;
    double optimum_;
    int per_decade_;
    std::int64_t step_ = 0;                // checkpoint k is ceil(10^(k / per_decade))
    std::int64_t next_checkpoint_;
    std::size_t next_target_ = 0;
    std::vector<std::int64_t> budget_checkpoints_;
    std::size_t next_budget_checkpoint_ = 0;
    AnytimeRecord record_;
};

}  // namespace mhb

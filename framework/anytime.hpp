#pragma once
// Anytime records, for runtime-to-target analysis as COCO and IOHprofiler do it: while a trial runs,
// the evaluator reports every evaluation to a recorder that keeps (1) the best-so-far f at
// log-spaced evaluation counts and (2) for each target precision (f - f*), the first evaluation that
// reached it. Both are exact to the evaluation, whatever population the optimiser evaluates at once.
#include <cstdint>
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
    bool operator==(const AnytimeSpec&) const = default;
};

// COCO's default targets for runtime ECDFs: 10^2 down to 10^-8, five per decade (51 values).
std::vector<double> bbob_targets();

// What one trial recorded.
struct AnytimeRecord {
    std::vector<std::int64_t> evaluations;  // checkpoints reached (1, 2, 3, 4, 7, 10, 16, ... at 5 per decade)
    std::vector<double> best;               // best-so-far f after that many evaluations
    std::vector<std::int64_t> hits;         // per target: the first evaluation with f - f* <= target; 0: never
    std::vector<double> hit_best;           // per target: the best-so-far f at that evaluation (NaN: never)
    bool empty() const { return evaluations.empty() && hits.empty(); }
};

class AnytimeRecorder {
public:
    // `optimum`: the problem's f*. Targets are taken from `spec` (decreasing).
    AnytimeRecorder(const AnytimeSpec& spec, double optimum);

    // The best-so-far `best` after evaluation number `count` (1-based, each count once, in order).
    void observe(std::int64_t count, double best) {
        while (count >= next_checkpoint_) {
            if (count == next_checkpoint_) {
                record_.evaluations.push_back(count);
                record_.best.push_back(best);
            }
            advance_checkpoint();
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
    AnytimeRecord record_;
};

}  // namespace mhb

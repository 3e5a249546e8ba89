#include "framework/anytime.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mhb {

std::vector<double> bbob_targets() {
    std::vector<double> out;
    // Exact powers of ten at every fifth target, so a target written 1e-3 in a config matches one here.
    for (int k = 10; k >= -40; --k) out.push_back(k % 5 == 0 ? std::pow(10.0, k / 5) : std::pow(10.0, k / 5.0));
    return out;
}

bool set_named_checkpoints(AnytimeSpec& spec, const std::string& name) {
    if (name == "cec2017") {
        spec.checkpoints = {0.01, 0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0};
        spec.checkpoint_exponents.clear();
    } else if (name == "cec2022") {
        spec.checkpoints.clear();
        spec.checkpoint_exponents.clear();
        for (int k = 0; k <= 15; ++k) spec.checkpoint_exponents.push_back(k / 5.0 - 3.0);
    } else {
        return false;
    }
    spec.checkpoints_rule = name;
    return true;
}

std::vector<std::int64_t> checkpoint_evaluations(const AnytimeSpec& spec, int dimension, std::int64_t max_evaluations) {
    std::vector<std::int64_t> out;
    if (max_evaluations <= 0) return out;
    auto add = [&](double fraction) {
        // The 1e-12 keeps a fraction that is a whole share (0.3 of 100000, D^0 = 1) from rounding one below.
        const auto count = static_cast<std::int64_t>(std::floor(fraction * static_cast<double>(max_evaluations) * (1.0 + 1e-12)));
        const std::int64_t at = std::clamp<std::int64_t>(count, 1, max_evaluations);
        if (out.empty() || at > out.back()) out.push_back(at);
    };
    for (double f : spec.checkpoints) add(f);
    for (double e : spec.checkpoint_exponents) add(std::pow(static_cast<double>(dimension), e));
    return out;
}

AnytimeRecorder::AnytimeRecorder(const AnytimeSpec& spec, double optimum, std::vector<std::int64_t> checkpoints)
    : targets_(spec.targets), optimum_(optimum), per_decade_(spec.points_per_decade),
      next_checkpoint_(spec.points_per_decade > 0 ? 1 : std::numeric_limits<std::int64_t>::max()),
      budget_checkpoints_(std::move(checkpoints)) {
    record_.hits.assign(targets_.size(), 0);
    record_.hit_best.assign(targets_.size(), std::numeric_limits<double>::quiet_NaN());
    record_.evaluations.reserve(128);
    record_.best.reserve(128);
}

void AnytimeRecorder::advance_checkpoint() {
    // Counts rounded up, duplicates skipped: at 5 per decade 1, 2, 3, 4, 7, 10, 16, 26, 40, 64, 100, ...
    const std::int64_t current = next_checkpoint_;
    while (next_checkpoint_ <= current) {
        ++step_;
        const double value = std::pow(10.0, static_cast<double>(step_) / per_decade_);
        if (value >= 9.2e18) {
            next_checkpoint_ = std::numeric_limits<std::int64_t>::max();
            return;
        }
        // Powers of ten land on their integer even where pow rounds a hair above it.
        next_checkpoint_ = static_cast<std::int64_t>(std::ceil(value * (1.0 - 1e-12)));
    }
}

}  // namespace mhb

#include "framework/anytime.hpp"

#include <cmath>
#include <limits>

namespace mhb {

std::vector<double> bbob_targets() {
    std::vector<double> out;
    // Exact powers of ten at every fifth target, so a target written 1e-3 in a config matches one here.
    for (int k = 10; k >= -40; --k) out.push_back(k % 5 == 0 ? std::pow(10.0, k / 5) : std::pow(10.0, k / 5.0));
    return out;
}

AnytimeRecorder::AnytimeRecorder(const AnytimeSpec& spec, double optimum)
    : targets_(spec.targets), optimum_(optimum), per_decade_(spec.points_per_decade),
      next_checkpoint_(spec.points_per_decade > 0 ? 1 : std::numeric_limits<std::int64_t>::max()) {
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

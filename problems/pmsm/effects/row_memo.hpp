#pragma once
// A per-row value of an expensive function (pow, sincos) of a block's rows, remembered by value
// between the predictions of the same block. A fit's Jacobian predicts each block of 512 rows many
// times with most parameters unchanged (the affine split's lanes, each linear column, the other
// parameters' differences), so an effect whose per-row argument does not change between them can
// take the function's earlier value instead of calling it again. The value is the one the function
// gave for the same argument and parameter, so predictions are the same to the bit: a row is a hit
// only when both are bit for bit the remembered ones (not merely equal: -0 and +0 differ).
#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace mhb::pmsm {

// `Slots` parameter values are kept (the least recently used one replaced): a parameter's two
// differences beside its value are three. One per thread (thread_local) and per use.
template <class Value, std::size_t Slots = 3>
class RowMemo {
public:
    // Blocks longer than this are computed without remembering (a model evaluates 512 rows at once).
    static constexpr Eigen::Index most_rows = 4096;

    // compute(argument(j)) for j < n, valid until the next call on this memo. `parameter` is the
    // value of the effect's parameter that compute and the arguments are made with.
    template <class Argument, class Compute>
    const Value* of(double parameter, Eigen::Index n, Argument argument, Compute compute) {
        const auto rows = static_cast<std::size_t>(n);
        if (n > most_rows) {
            scratch_.resize(rows);
            for (std::size_t j = 0; j < rows; ++j) scratch_[j] = compute(argument(static_cast<Eigen::Index>(j)));
            return scratch_.data();
        }
        ++clock_;
        Slot* slot = nullptr;
        for (auto& candidate : slots_)
            if (candidate.used != 0 && same(candidate.parameter, parameter)) slot = &candidate;
        if (slot == nullptr) {
            slot = &slots_[0];
            for (auto& candidate : slots_)
                if (candidate.used < slot->used) slot = &candidate;
            slot->parameter = parameter;
            slot->arguments.clear();
        }
        slot->used = clock_;
        const std::size_t known = std::min(rows, slot->arguments.size());
        slot->arguments.resize(std::max(rows, slot->arguments.size()));
        slot->values.resize(slot->arguments.size());
        for (std::size_t j = 0; j < rows; ++j) {
            const double x = argument(static_cast<Eigen::Index>(j));
            if (j < known && same(slot->arguments[j], x)) continue;
            slot->arguments[j] = x;
            slot->values[j] = compute(x);
        }
        return slot->values.data();
    }

private:
    static bool same(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

    struct Slot {
        double parameter = 0.0;
        std::vector<double> arguments;
        std::vector<Value> values;
        unsigned long used = 0;  // 0: empty
    };
    std::array<Slot, Slots> slots_;
    unsigned long clock_ = 0;
    std::vector<Value> scratch_;
};

}  // namespace mhb::pmsm

#pragma once
// A shifted sphere that keeps every population it is asked to evaluate, with the fitness it returned,
// so that tests can replay an optimiser's moves from outside. Single-threaded tests only: recording
// is the mutable state a real problem must not have.
#include <vector>

#include "tests/sphere_fixture.hpp"

namespace mhb::testing {

class RecordingSphere final : public Problem {
public:
    struct Batch {
        Matrix x;
        Vector f;
    };

    RecordingSphere(int dimension, double lower, double upper, double shift) : sphere_(dimension, lower, upper, shift) {
        set_domain(dimension, lower, upper);
        truth_ = sphere_.truth();
    }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        sphere_.evaluate(x, f);
        batches_.push_back({x, f});
    }
    const std::vector<Batch>& batches() const { return batches_; }

private:
    ShiftedSphere sphere_;
    mutable std::vector<Batch> batches_;
};

}  // namespace mhb::testing

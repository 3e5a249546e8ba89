#pragma once
// A shifted sphere with a known optimum, for testing the framework without depending on plugins.
#include "framework/problem.hpp"

namespace mhb::testing {

class ShiftedSphere final : public Problem {
public:
    ShiftedSphere(int dimension, double lower, double upper, double shift) : shift_(shift) {
        set_domain(dimension, lower, upper);
        truth_.optimum_value = 0.0;
        truth_.true_parameters = Vector::Constant(dimension, shift);
    }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        f = (x.array() - shift_).square().colwise().sum().transpose();
    }

private:
    double shift_;
};

}  // namespace mhb::testing

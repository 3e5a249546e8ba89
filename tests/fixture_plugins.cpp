// Plugins that exist only in the test binary: a sphere with a known optimum, a problem that
// returns NaN in part of its box, and an optimiser that throws, to test the framework's handling.
#include <stdexcept>

#include "framework/registry.hpp"
#include "tests/sphere_fixture.hpp"

namespace mhb::testing {
namespace {

class NanProblem final : public Problem {
public:
    NanProblem() { set_domain(2, -1, 1); }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        for (Eigen::Index i = 0; i < x.cols(); ++i) f[i] = x(0, i) > 0.9 ? std::nan("") : x.col(i).squaredNorm();
    }
};

class ThrowingOptimizer final : public Optimizer {
public:
    explicit ThrowingOptimizer(std::int64_t at) : at_(at) {}
    void initialize(Evaluator& ev, Rng& rng) override {
        x_.resize(ev.dimension(), 4);
        f_.resize(4);
        fill_uniform(x_, ev.bounds(), rng);
        ev.evaluate(x_, f_);
    }
    void iterate(const Progress& p, Evaluator& ev, Rng& rng) override {
        if (p.iteration == at_) throw std::runtime_error("deliberate failure at iteration " + std::to_string(at_));
        fill_uniform(x_, ev.bounds(), rng);
        ev.evaluate(x_, f_);
    }

private:
    std::int64_t at_;
    Matrix x_;
    Vector f_;
};

const bool sphere_registered = register_problem({
    "test_sphere",
    "shifted sphere (test only)",
    {ParameterSpec::integer("dimension", 3, 1, 50, "dimension"), ParameterSpec::real("shift", 1.0, -4, 4, "optimum location")},
    [](const ParameterSet& p, const ProblemContext&) {
        return std::make_unique<ShiftedSphere>(static_cast<int>(p.integer("dimension")), -5.0, 5.0, p.real("shift"));
    },
});

const bool nan_registered = register_problem({
    "test_nan", "returns NaN for x1 > 0.9 (test only)", {},
    [](const ParameterSet&, const ProblemContext&) { return std::make_unique<NanProblem>(); },
});

const bool throwing_registered = register_optimizer({
    "test_throwing", "throws at a given iteration (test only)",
    {ParameterSpec::integer("at", 3, 0, 1000, "iteration that throws (0 = never)")},
    [](const ParameterSet& p) { return std::make_unique<ThrowingOptimizer>(p.integer("at")); },
});

}  // namespace
}  // namespace mhb::testing

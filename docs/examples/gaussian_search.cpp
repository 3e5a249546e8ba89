// A worked example of an optimizer plugin (docs/architecture.md): each individual tries a Gaussian
// step around itself and keeps it if it is better; the step shrinks from 20 % to 0.1 % of the box
// as the budget is used. Simple on purpose; it shows the interface, not a method to publish.
#include "framework/registry.hpp"

namespace mhb {
namespace {

class GaussianSearch final : public Optimizer {
public:
    explicit GaussianSearch(const ParameterSet& p) : n_(p.integer("population")) {}

    void initialize(Evaluator& ev, Rng& rng) override {
        x_.resize(ev.dimension(), n_);  // allocate once, here
        trial_.resize(ev.dimension(), n_);
        f_.resize(n_);
        f_trial_.resize(n_);
        fill_uniform(x_, ev.bounds(), rng);
        ev.evaluate(x_, f_);  // the whole population at once
    }

    void iterate(const Progress& progress, Evaluator& ev, Rng& rng) override {
        const double t = progress.fraction();  // t/T under iteration or evaluation budgets
        const double step = 0.2 * std::pow(0.005, t);
        const auto& box = ev.bounds();
        for (Eigen::Index i = 0; i < n_; ++i)
            for (Eigen::Index j = 0; j < x_.rows(); ++j)
                trial_(j, i) = x_(j, i) + step * (box.upper[j] - box.lower[j]) * rng.normal();
        clamp_to_bounds(trial_, box);  // the evaluator refuses points outside the box
        ev.evaluate(trial_, f_trial_);
        for (Eigen::Index i = 0; i < n_; ++i)
            if (f_trial_[i] < f_[i]) {
                x_.col(i) = trial_.col(i);
                f_[i] = f_trial_[i];
            }
    }

private:
    Eigen::Index n_;
    Matrix x_, trial_;
    Vector f_, f_trial_;
};

const bool registered = register_optimizer({
    "example_gaussian_search",
    "Worked example from docs/architecture.md: greedy Gaussian steps shrinking with the budget",
    {ParameterSpec::integer("population", 20, 1, 100000, "individuals, each stepping around itself")},
    [](const ParameterSet& p) { return std::make_unique<GaussianSearch>(p); }});

}  // namespace
}  // namespace mhb

// Pure random search: uniform samples in the box, one batch per iteration. The baseline every
// metaheuristic must beat, and the optimiser that proves the pipeline end to end.
#include "framework/registry.hpp"

namespace mhb {
namespace {

class RandomSearch final : public Optimizer {
public:
    explicit RandomSearch(const ParameterSet& p) : batch_(static_cast<Eigen::Index>(p.integer("batch"))) {}

    void initialize(Evaluator& evaluator, Rng& rng) override {
        samples_.resize(evaluator.dimension(), batch_);
        fitness_.resize(batch_);
        sample(evaluator, rng);
    }
    void iterate(const Progress&, Evaluator& evaluator, Rng& rng) override { sample(evaluator, rng); }

private:
    void sample(Evaluator& evaluator, Rng& rng) {
        fill_uniform(samples_, evaluator.bounds(), rng);
        evaluator.evaluate(samples_, fitness_);
    }
    Eigen::Index batch_;
    Matrix samples_;
    Vector fitness_;
};

const bool registered = register_optimizer({
    "random_search",
    "Uniform random sampling of the box, one batch per iteration",
    {ParameterSpec::integer("batch", 100, 1, 1'000'000, "samples drawn and evaluated per iteration")},
    [](const ParameterSet& p) { return std::make_unique<RandomSearch>(p); },
});

}  // namespace
}  // namespace mhb

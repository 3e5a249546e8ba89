#pragma once
// An optimizer that does nothing: the fixtures test loading, not optimising.
#include <memory>

#include "framework/registry.hpp"

namespace fixture {

class IdleOptimizer final : public mhb::Optimizer {
public:
    void initialize(mhb::Evaluator&, mhb::Rng&) override {}
    void iterate(const mhb::Progress&, mhb::Evaluator&, mhb::Rng&) override {}
};

inline bool register_idle_optimizer(const char* name, const char* summary) {
    return mhb::register_optimizer({name, summary, {}, [](const mhb::ParameterSet&) { return std::make_unique<IdleOptimizer>(); }});
}

}  // namespace fixture

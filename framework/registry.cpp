#include "framework/registry.hpp"

namespace mhb {

std::vector<ListedRegistry>& listed_registries() {
    static std::vector<ListedRegistry> registries;
    return registries;
}

namespace {
const bool optimizers_listed = list_registry<OptimizerFactory>("optimizers");
const bool problems_listed = list_registry<ProblemFactory>("problems");
}  // namespace

std::unique_ptr<Optimizer> make_optimizer(const std::string& name, const std::map<std::string, ParameterValue>& values) {
    const auto& entry = OptimizerRegistry::instance().at(name, "optimizer");
    return entry.create(ParameterSet(entry.parameters, values));
}

std::unique_ptr<Problem> make_problem(const std::string& name, const std::map<std::string, ParameterValue>& values,
                                      const ProblemContext& context) {
    const auto& entry = ProblemRegistry::instance().at(name, "problem");
    return entry.create(ParameterSet(entry.parameters, values), context);
}

}  // namespace mhb

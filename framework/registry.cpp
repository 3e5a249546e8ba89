#include "framework/registry.hpp"

#include <fmt/format.h>

namespace mhb {

namespace {
std::string& current_origin() {
    static std::string origin = "built-in";
    return origin;
}
std::vector<std::function<std::vector<std::string>()>>& clash_sources() {
    static std::vector<std::function<std::vector<std::string>()>> sources;
    return sources;
}
// "the built-in effect 'x'" or "the effect 'x' of /p/lib.so".
std::string described(const std::string& kind, const std::string& name, const std::string& origin) {
    return origin == "built-in" ? fmt::format("the built-in {} '{}'", kind, name) : fmt::format("the {} '{}' of {}", kind, name, origin);
}
}  // namespace

const std::string& registration_origin() { return current_origin(); }
void set_registration_origin(std::string origin) { current_origin() = std::move(origin); }

std::string clash_message(const std::string& kind, const RegistrationClash& clash) {
    return described(kind, clash.name, clash.second_origin) + " clashes with " + described(kind, clash.name, clash.first_origin) +
           "; rename one of them";
}

std::vector<ListedRegistry>& listed_registries() {
    static std::vector<ListedRegistry> registries;
    return registries;
}

void add_clash_source(std::function<std::vector<std::string>()> source) { clash_sources().push_back(std::move(source)); }

std::vector<std::string> registration_clashes() {
    std::vector<std::string> out;
    for (const auto& registry : listed_registries()) {
        const std::string kind = registry.kind.ends_with('s') ? registry.kind.substr(0, registry.kind.size() - 1) : registry.kind;
        for (const auto& clash : registry.conflicts()) out.push_back(clash_message(kind, clash));
    }
    for (const auto& source : clash_sources())
        for (auto& message : source()) out.push_back(std::move(message));
    return out;
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

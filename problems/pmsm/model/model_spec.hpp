#pragma once
// A model to fit: the base steady-state dq model plus a list of effects, written
//   base+deadtime+delay(tau=150e-6)
// An effect written with values in parentheses has those parameters fixed (a controller's delay is
// known by design); the others are fitted within their declared plausible ranges.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "problems/pmsm/model/steady_state_model.hpp"

namespace mhb::pmsm {

struct EffectTerm {
    std::string name;                     // registered effect name, as registered (canonical case)
    std::map<std::string, double> fixed;  // parameter -> value held fixed in the fit
};

struct ModelSpec {
    std::vector<EffectTerm> effects;

    // "base", "base+deadtime", "base+delay(tau=0.00015)": parses back to the same spec.
    std::string text() const;
    bool contains(const std::string& effect) const;
    // This spec with one more effect (its parameters all free).
    ModelSpec with(const std::string& effect) const;
    // This spec less one effect (no change when it has none of that name).
    ModelSpec without(const std::string& effect) const;
    // The first `count` effects: base+A+B -> base+A for count 1.
    ModelSpec prefix(std::size_t count) const;
};

// Parses a model spec. Throws InputError (file "--model") on a spec that does not start with base,
// an unknown effect (the message lists the registered ones), an effect named twice, an unknown or
// non-real parameter, a malformed or non-finite value, or a value outside the parameter's declared range.
ModelSpec parse_model_spec(const std::string& text);

// The effects of a spec, created with their fixed values (free parameters at their defaults).
std::vector<std::unique_ptr<Effect>> make_effects(const ModelSpec& spec);

// The steady-state model of `spec` on `data`; InputError naming the column when an effect needs one
// the data lack.
// The model refers to `data`, which must outlive it; from a temporary, it keeps the data.
std::unique_ptr<SteadyStateModel> make_model(const ModelSpec& spec, const Measurement& data);
std::unique_ptr<SteadyStateModel> make_model(const ModelSpec& spec, Measurement&& data);

// Which parameters of make_model(spec, ...) are fitted: the four base parameters and every effect
// parameter not fixed by the spec (same order as SteadyStateModel::parameter_names()).
std::vector<bool> free_parameters(const ModelSpec& spec);

// Whether an effect's declared range is a full turn of an angle (it then wraps instead of ending).
bool is_periodic(const ParameterSpec& spec);

}  // namespace mhb::pmsm

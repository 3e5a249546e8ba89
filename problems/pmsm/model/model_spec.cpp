#include "problems/pmsm/model/model_spec.hpp"

#include <charconv>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "framework/input_error.hpp"

namespace mhb::pmsm {
namespace {

std::string trim(const std::string& s) {
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string::npos) return {};
    const auto e = s.find_last_not_of(" \t");
    return s.substr(b, e - b + 1);
}

[[noreturn]] void refuse(const std::string& field, const std::string& message) {
    throw InputError("--model", 0, field, message);
}

std::string registered_effects() {
    std::string names;
    for (const auto* e : EffectRegistry::instance().entries()) names += (names.empty() ? "" : ", ") + e->name;
    return names;
}

// Splits at `separator` outside parentheses.
std::vector<std::string> split_top_level(const std::string& text, char separator) {
    std::vector<std::string> parts;
    std::string current;
    int depth = 0;
    for (char c : text) {
        if (c == '(') ++depth;
        if (c == ')') --depth;
        if (c == separator && depth == 0) {
            parts.push_back(current);
            current.clear();
        } else {
            current += c;
        }
    }
    parts.push_back(current);
    return parts;
}

EffectTerm parse_term(const std::string& raw) {
    const std::string term = trim(raw);
    EffectTerm out;
    const auto open = term.find('(');
    const std::string name = trim(term.substr(0, open));
    if (name.empty()) refuse(term, "an empty effect name (two '+' in a row, or a '+' at the end?)");
    const auto* entry = EffectRegistry::instance().find(name);
    if (!entry) refuse(name, fmt::format("unknown effect; registered effects: {}", registered_effects()));
    out.name = entry->name;
    if (open == std::string::npos) return out;
    if (term.back() != ')' || term.find('(', open + 1) != std::string::npos || term.find(')') != term.size() - 1)
        refuse(term, "expected NAME(parameter=value, ...)");
    const std::string inside = term.substr(open + 1, term.size() - open - 2);
    for (const auto& assignment : split_top_level(inside, ',')) {
        const auto eq = assignment.find('=');
        if (eq == std::string::npos) refuse(out.name, fmt::format("expected parameter=value, got '{}'", trim(assignment)));
        const std::string key = trim(assignment.substr(0, eq)), value_text = trim(assignment.substr(eq + 1));
        const ParameterSpec* spec = nullptr;
        std::string known;
        for (const auto& p : entry->parameters) {
            if (p.type != ParameterType::Real) continue;
            known += (known.empty() ? "" : ", ") + p.name;
            if (p.name == key) spec = &p;
        }
        const std::string field = out.name + "." + key;
        if (!spec) refuse(field, fmt::format("not a fitted parameter of {}; its parameters: {}", out.name, known));
        if (out.fixed.count(key)) refuse(field, "given twice");
        double value = 0.0;
        const char* first = value_text.data();
        const char* last = first + value_text.size();
        if (!value_text.empty() && *first == '+') ++first;
        const auto [end, ec] = std::from_chars(first, last, value);
        if (value_text.empty() || ec != std::errc() || end != last || !std::isfinite(value))
            refuse(field, fmt::format("not a finite number: '{}'", value_text));
        if (value < spec->minimum || value > spec->maximum)
            refuse(field, fmt::format("{} is outside the plausible range {}{}", value_text, spec->range_text(),
                                      spec->unit.empty() ? "" : " " + spec->unit));
        out.fixed[key] = value;
    }
    return out;
}

}  // namespace

std::string ModelSpec::text() const {
    std::string out = "base";
    for (const auto& e : effects) {
        out += "+" + e.name;
        if (e.fixed.empty()) continue;
        std::string args;
        // Declaration order, so the text reads as the effect declares its parameters.
        for (const auto& p : EffectRegistry::instance().at(e.name, "effect").parameters)
            if (auto it = e.fixed.find(p.name); it != e.fixed.end())
                args += fmt::format("{}{}={}", args.empty() ? "" : ",", p.name, it->second);
        out += "(" + args + ")";
    }
    return out;
}

bool ModelSpec::contains(const std::string& effect) const {
    for (const auto& e : effects)
        if (e.name == effect) return true;
    return false;
}

ModelSpec ModelSpec::with(const std::string& effect) const {
    ModelSpec out = *this;
    out.effects.push_back({EffectRegistry::instance().at(effect, "effect").name, {}});
    return out;
}

ModelSpec ModelSpec::without(const std::string& effect) const {
    ModelSpec out = *this;
    std::erase_if(out.effects, [&](const EffectTerm& e) { return e.name == effect; });
    return out;
}

ModelSpec ModelSpec::prefix(std::size_t count) const {
    ModelSpec out;
    out.effects.assign(effects.begin(), effects.begin() + static_cast<std::ptrdiff_t>(std::min(count, effects.size())));
    return out;
}

ModelSpec parse_model_spec(const std::string& text) {
    const auto terms = split_top_level(text, '+');
    int depth = 0;
    for (char c : text) {
        depth += c == '(' ? 1 : c == ')' ? -1 : 0;
        if (depth < 0 || depth > 1) refuse(text, "unbalanced or nested parentheses");
    }
    if (depth != 0) refuse(text, "unbalanced parentheses");
    if (trim(terms.front()) != "base")
        refuse(trim(terms.front()), "a model starts with base (e.g. base+deadtime+delay(tau=150e-6))");
    ModelSpec spec;
    for (std::size_t k = 1; k < terms.size(); ++k) {
        EffectTerm term = parse_term(terms[k]);
        if (spec.contains(term.name)) refuse(term.name, "named twice");
        spec.effects.push_back(std::move(term));
    }
    return spec;
}

std::vector<std::unique_ptr<Effect>> make_effects(const ModelSpec& spec) {
    std::vector<std::unique_ptr<Effect>> effects;
    for (const auto& e : spec.effects) {
        std::map<std::string, ParameterValue> values;
        for (const auto& [k, v] : e.fixed) values[k] = v;
        effects.push_back(make_effect(e.name, values));
    }
    return effects;
}

std::unique_ptr<SteadyStateModel> make_model(const ModelSpec& spec, const Measurement& data) {
    return std::make_unique<SteadyStateModel>(data, make_effects(spec));
}

std::unique_ptr<SteadyStateModel> make_model(const ModelSpec& spec, Measurement&& data) {
    return std::make_unique<SteadyStateModel>(std::move(data), make_effects(spec));
}

std::vector<bool> free_parameters(const ModelSpec& spec) {
    std::vector<bool> free(base_parameter_names.size(), true);
    for (const auto& e : spec.effects)
        for (const auto& p : EffectRegistry::instance().at(e.name, "effect").parameters)
            if (p.type == ParameterType::Real) free.push_back(e.fixed.count(p.name) == 0);
    return free;
}

bool is_periodic(const ParameterSpec& spec) {
    return spec.unit == "rad" && std::abs(spec.maximum - spec.minimum - 2.0 * std::numbers::pi) < 1e-12;
}

}  // namespace mhb::pmsm

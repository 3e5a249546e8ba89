#include "framework/parameters.hpp"

#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "framework/input_error.hpp"

namespace mhb {

std::string to_string(const ParameterValue& value) {
    return std::visit(
        [](const auto& v) -> std::string {
            using T = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<T, bool>) return v ? "true" : "false";
            else if constexpr (std::is_same_v<T, std::int64_t>) return std::to_string(v);
            else if constexpr (std::is_same_v<T, double>) return fmt::format("{:g}", v);
            else return v;
        },
        value);
}

const char* type_name(ParameterType type) {
    switch (type) {
        case ParameterType::Boolean: return "bool";
        case ParameterType::Integer: return "int";
        case ParameterType::Real: return "real";
        case ParameterType::Text: return "text";
    }
    return "?";
}

ParameterSpec ParameterSpec::real(std::string name, double def, double lo, double hi, std::string description,
                                  std::string unit) {
    ParameterSpec s;
    s.name = std::move(name);
    s.type = ParameterType::Real;
    s.default_value = def;
    s.minimum = lo;
    s.maximum = hi;
    s.description = std::move(description);
    s.unit = std::move(unit);
    return s;
}

ParameterSpec ParameterSpec::integer(std::string name, std::int64_t def, std::int64_t lo, std::int64_t hi,
                                     std::string description) {
    ParameterSpec s;
    s.name = std::move(name);
    s.type = ParameterType::Integer;
    s.default_value = def;
    s.minimum = static_cast<double>(lo);
    s.maximum = static_cast<double>(hi);
    s.description = std::move(description);
    return s;
}

ParameterSpec ParameterSpec::boolean(std::string name, bool def, std::string description) {
    ParameterSpec s;
    s.name = std::move(name);
    s.type = ParameterType::Boolean;
    s.default_value = def;
    s.description = std::move(description);
    return s;
}

ParameterSpec ParameterSpec::choice(std::string name, std::string def, std::vector<std::string> choices,
                                    std::string description) {
    ParameterSpec s;
    s.name = std::move(name);
    s.type = ParameterType::Text;
    s.default_value = std::move(def);
    s.choices = std::move(choices);
    s.description = std::move(description);
    return s;
}

ParameterSpec ParameterSpec::text(std::string name, std::string def, std::string description) {
    return choice(std::move(name), std::move(def), {}, std::move(description));
}

std::string ParameterSpec::range_text() const {
    switch (type) {
        case ParameterType::Boolean: return "{true, false}";
        case ParameterType::Text: {
            if (choices.empty()) return "";
            std::string out = "{";
            for (std::size_t i = 0; i < choices.size(); ++i) out += (i ? ", " : "") + choices[i];
            return out + "}";
        }
        case ParameterType::Integer:
        case ParameterType::Real: {
            auto bound = [this](double b) {
                if (std::isinf(b)) return std::string(b < 0 ? "-inf" : "inf");
                return type == ParameterType::Integer ? fmt::format("{}", static_cast<long long>(b))
                                                      : fmt::format("{:g}", b);
            };
            return "[" + bound(minimum) + ", " + bound(maximum) + "]";
        }
    }
    return "";
}

ParameterValue ParameterSpec::check(const ParameterValue& value) const {
    auto fail = [&](const std::string& why) -> ParameterError {
        return ParameterError(name, fmt::format("{} (got {})", why, to_string(value)));
    };
    switch (type) {
        case ParameterType::Boolean:
            if (!std::holds_alternative<bool>(value)) throw fail("expects true or false");
            return value;
        case ParameterType::Text: {
            if (!std::holds_alternative<std::string>(value)) throw fail("expects a string");
            const auto& v = std::get<std::string>(value);
            if (!choices.empty()) {
                for (const auto& c : choices)
                    if (c == v) return value;
                throw fail("expects one of " + range_text());
            }
            return value;
        }
        case ParameterType::Integer: {
            std::int64_t v;
            if (std::holds_alternative<std::int64_t>(value)) v = std::get<std::int64_t>(value);
            else throw fail("expects an integer");
            if (static_cast<double>(v) < minimum || static_cast<double>(v) > maximum)
                throw fail("must lie in " + range_text());
            return v;
        }
        case ParameterType::Real: {
            double v;
            if (std::holds_alternative<double>(value)) v = std::get<double>(value);
            else if (std::holds_alternative<std::int64_t>(value)) v = static_cast<double>(std::get<std::int64_t>(value));
            else throw fail("expects a number");
            if (!std::isfinite(v)) throw fail("must be finite");
            if (v < minimum || v > maximum) throw fail("must lie in " + range_text());
            return v;
        }
    }
    return value;
}

ParameterSet::ParameterSet(const std::vector<ParameterSpec>& specs,
                           const std::map<std::string, ParameterValue>& given)
    : specs_(specs) {
    for (const auto& s : specs_) {
        values_[s.name] = s.default_value;
        defaults_[s.name] = s.default_value;
    }
    for (const auto& [name, value] : given) {
        const ParameterSpec* spec = nullptr;
        for (const auto& s : specs_)
            if (s.name == name) spec = &s;
        if (!spec) {
            std::string known;
            for (const auto& s : specs_) known += (known.empty() ? "" : ", ") + s.name;
            throw ParameterError(name, "unknown parameter; known: " + (known.empty() ? "(none)" : known));
        }
        values_[name] = spec->check(value);
    }
}

const ParameterValue& ParameterSet::value(const std::string& name) const {
    auto it = values_.find(name);
    if (it == values_.end()) throw ParameterError(name, "no such parameter (plugin asked for an undeclared name)");
    return it->second;
}

double ParameterSet::real(const std::string& name) const {
    const auto& v = value(name);
    if (std::holds_alternative<std::int64_t>(v)) return static_cast<double>(std::get<std::int64_t>(v));
    return std::get<double>(v);
}
std::int64_t ParameterSet::integer(const std::string& name) const { return std::get<std::int64_t>(value(name)); }
bool ParameterSet::boolean(const std::string& name) const { return std::get<bool>(value(name)); }
const std::string& ParameterSet::text(const std::string& name) const { return std::get<std::string>(value(name)); }

std::string ParameterSet::non_default_text() const {
    std::string out;
    for (const auto& s : specs_) {
        const auto& v = values_.at(s.name);
        if (to_string(v) == to_string(defaults_.at(s.name))) continue;
        out += (out.empty() ? "" : ",") + s.name + "=" + to_string(v);
    }
    return out;
}

}  // namespace mhb

#pragma once
// Typed plugin parameters: each plugin declares its parameters (type, default, range, one-line
// description); user values are checked against the declaration before anything runs.
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <variant>
#include <vector>

namespace mhb {

enum class ParameterType { Boolean, Integer, Real, Text };

using ParameterValue = std::variant<bool, std::int64_t, double, std::string>;

std::string to_string(const ParameterValue& value);
const char* type_name(ParameterType type);

struct ParameterSpec {
    std::string name;
    ParameterType type = ParameterType::Real;
    ParameterValue default_value;
    double minimum = -std::numeric_limits<double>::infinity();
    double maximum = std::numeric_limits<double>::infinity();
    std::vector<std::string> choices;  // for Text: the allowed values (empty = any)
    std::string description;
    std::string unit;

    static ParameterSpec real(std::string name, double def, double lo, double hi, std::string description,
                              std::string unit = {});
    static ParameterSpec integer(std::string name, std::int64_t def, std::int64_t lo, std::int64_t hi,
                                 std::string description);
    static ParameterSpec boolean(std::string name, bool def, std::string description);
    static ParameterSpec choice(std::string name, std::string def, std::vector<std::string> choices,
                                std::string description);
    static ParameterSpec text(std::string name, std::string def, std::string description);

    // "[0, 1]" or "{a, b}" or "" : what values are accepted, for listings and messages.
    std::string range_text() const;
    // Converts and checks a user value; throws ParameterError naming this parameter.
    ParameterValue check(const ParameterValue& value) const;
};

class ParameterSet {
public:
    ParameterSet() = default;
    // Defaults overridden by `given`; unknown names and bad values throw ParameterError.
    ParameterSet(const std::vector<ParameterSpec>& specs, const std::map<std::string, ParameterValue>& given);

    double real(const std::string& name) const;
    std::int64_t integer(const std::string& name) const;
    bool boolean(const std::string& name) const;
    const std::string& text(const std::string& name) const;
    const ParameterValue& value(const std::string& name) const;
    bool contains(const std::string& name) const { return values_.count(name) != 0; }
    const std::map<std::string, ParameterValue>& values() const { return values_; }
    // Parameters that differ from their defaults, "a=1,b=x", in declaration order.
    std::string non_default_text() const;

private:
    std::vector<ParameterSpec> specs_;
    std::map<std::string, ParameterValue> values_;
    std::map<std::string, ParameterValue> defaults_;
};

}  // namespace mhb

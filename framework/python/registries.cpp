// mhbench.plugins(kind), optimizers(), problems(): what `mhbench list` shows, as Python data.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "framework/python/python_bindings.hpp"
#include "framework/registry.hpp"

namespace mhb::python {
namespace {

py::dict parameter_dict(const ParameterSpec& p) {
    py::dict d;
    d["name"] = p.name;
    d["type"] = type_name(p.type);
    d["default"] = python_value(p.default_value);
    const bool numeric = p.type == ParameterType::Integer || p.type == ParameterType::Real;
    auto limit = [&](double v) -> py::object {
        if (!numeric || std::isinf(v)) return py::none();
        if (p.type == ParameterType::Integer) return py::int_(static_cast<long long>(v));
        return py::float_(v);
    };
    d["minimum"] = limit(p.minimum);
    d["maximum"] = limit(p.maximum);
    d["choices"] = p.choices;
    d["range"] = p.range_text();
    d["unit"] = p.unit;
    d["description"] = p.description;
    return d;
}

py::list plugins_of(const std::string& kind) {
    auto& registries = listed_registries();
    std::vector<std::string> kinds;
    for (const auto& r : registries) {
        kinds.push_back(r.kind);
        if (r.kind != kind) continue;
        const auto names = r.names_and_summaries();
        const auto parameters = r.parameters();
        py::list out;
        for (std::size_t i = 0; i < names.size(); ++i) {
            py::dict entry;
            entry["name"] = names[i].first;
            entry["summary"] = names[i].second;
            py::list specs;
            for (const auto& p : parameters[i]) specs.append(parameter_dict(p));
            entry["parameters"] = specs;
            out.append(entry);
        }
        return out;
    }
    std::sort(kinds.begin(), kinds.end());
    throw_input_error("kind", fmt::format("unknown kind '{}'; expected one of {}", kind, fmt::join(kinds, ", ")));
}

}  // namespace

void bind_registries(py::module_& m) {
    m.def("plugins", &plugins_of, py::arg("kind"),
          "Every registered plugin of one kind ('optimizers', 'problems', 'effects', ...): a list of dicts with name, "
          "summary and parameters (name, type, default, minimum, maximum, choices, range, unit, description).");
    m.def("plugin_kinds", [] {
        std::vector<std::string> kinds;
        for (const auto& r : listed_registries()) kinds.push_back(r.kind);
        std::sort(kinds.begin(), kinds.end());
        return kinds;
    });
}

}  // namespace mhb::python

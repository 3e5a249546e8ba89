// mhbench._mhbench: the extension module under the Python package mhbench (docs/python.md).
#include <pybind11/pybind11.h>

#include "framework/python/python_bindings.hpp"
#include "framework/random.hpp"

namespace mhb::python {
namespace {

std::map<std::string, std::function<void(py::module_&)>>& submodules() {
    static std::map<std::string, std::function<void(py::module_&)>> all;
    return all;
}

}  // namespace

bool register_submodule(std::string name, std::function<void(py::module_&)> bind) {
    return submodules().emplace(std::move(name), std::move(bind)).second;
}

void bind_submodules(py::module_& m) {
    for (const auto& [name, bind] : submodules()) {
        auto sub = m.def_submodule(name.c_str());
        bind(sub);
    }
}

}  // namespace mhb::python

PYBIND11_MODULE(_mhbench, m) {
    namespace py = pybind11;
    using namespace mhb::python;
    m.doc() = "mhbench's core and built-in plugins; use the package mhbench (docs/python.md)";
    bind_errors(m);
    bind_registries(m);
    bind_problems(m);
    bind_minimize(m);
    bind_experiments(m);
    bind_python_plugins(m);
    m.def(
        "trial_seed",
        [](py::handle master, const std::string& optimizer, const std::string& problem, py::handle trial) {
            const auto index = integer_of(trial, "trial", 0);
            if (!index) throw py::type_error("trial: expects an integer >= 0, got None");
            return mhb::derive_seed(seed_of(master, "master_seed"), optimizer, problem, static_cast<std::uint64_t>(*index));
        },
        py::arg("master_seed"), py::arg("optimizer"), py::arg("problem"), py::arg("trial"));
    bind_submodules(m);
}

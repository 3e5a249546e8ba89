#pragma once
// The Python module mhbench._mhbench: one file per part of its interface, and what the parts share
// (numpy arrays as populations, Python values as plugin parameters, Python errors raised inside a
// trial). The Python package framework/python/mhbench/ wraps it (docs/python.md).
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/pybind11.h>

#include "framework/input_error.hpp"
#include "framework/parameters.hpp"
#include "framework/problem.hpp"

namespace mhb::python {

namespace py = pybind11;

void bind_errors(py::module_& m);
void bind_registries(py::module_& m);
void bind_problems(py::module_& m);
void bind_minimize(py::module_& m);
void bind_experiments(py::module_& m);
void bind_python_plugins(py::module_& m);

// A plugin family's own bindings (problems/pmsm/python/) add a submodule from their own file, as its
// plugins register themselves: `const bool bound = register_submodule("pmsm", bind_pmsm);`.
bool register_submodule(std::string name, std::function<void(py::module_&)> bind);
void bind_submodules(py::module_& m);

// Raises mhbench.InputError naming `field` (an argument of the Python call, e.g. "options['population']").
[[noreturn]] void throw_input_error(const std::string& field, const std::string& message);

// Plugin parameter values from a dict {name: value} (None: no values); TypeError naming
// `argument`['name'] for a value that is not a bool, an integer, a real number or a string.
std::map<std::string, ParameterValue> parameter_values(py::handle options, const std::string& argument);
py::object python_value(const ParameterValue& value);

// Points handed in from Python as the framework's D x n population. A C-contiguous float64 (n, D)
// array is exactly a column-major D x n matrix, so it is used in place; any other real array is
// converted once. TypeError or ValueError naming `argument` for anything else, a wrong column count
// or a value that is not finite.
class Population {
public:
    // `dimension` < 0: any. A 1-D array is one point when `single_point_allowed`.
    Population(py::handle x, const std::string& argument, Eigen::Index dimension, bool single_point_allowed);
    Eigen::Map<const Matrix> points() const { return {data_, dimension_, count_}; }
    Eigen::Index count() const { return count_; }
    bool single_point() const { return single_point_; }
    // True when the caller's own memory is used (no copy was made).
    bool in_place() const { return in_place_; }

private:
    py::array array_;  // keeps the memory alive
    const double* data_ = nullptr;
    Eigen::Index count_ = 0, dimension_ = 0;
    bool single_point_ = false, in_place_ = false;
};

// The column count of `x` when it is a 2-D array-like (1-D: its length), before it is converted.
std::optional<Eigen::Index> columns_of(py::handle x);

// A D x n population as a new C-contiguous (n, D) array; a vector as a new 1-D array.
py::array_t<double> numpy_points(const Eigen::Ref<const Matrix>& x);
py::array_t<double> numpy_vector(const Eigen::Ref<const Vector>& v);

// A box from Python: an array-like of shape (D, 2), one (lower, upper) row per variable, as scipy
// takes it. ValueError naming `argument` for another shape, a bound that is not finite or
// lower > upper.
Bounds bounds_of(py::handle bounds, const std::string& argument);
py::array_t<double> numpy_bounds(const Bounds& bounds);

// The first Python exception raised inside a trial (by an objective, a callback or a plugin written
// in Python), kept so that the caller gets it, traceback and all, after the trial has stopped. The
// trial itself sees a PluginFault and fails as it would for a C++ fault.
class PythonFailure {
public:
    // Keeps the current Python error (the GIL held) and returns the fault to throw into the trial.
    PluginFault keep(py::error_already_set&& error, const std::string& where);
    bool kept() const;
    // Raises the kept error in Python, if there is one (the GIL held).
    void rethrow_if_kept();

private:
    mutable std::mutex mutex_;
    std::optional<py::error_already_set> error_;
};

// While it lives, the Python exceptions of plugins written in Python that run on this thread are
// kept in `failure` (minimize runs its trial on the caller's thread). Elsewhere (the experiment
// runner's threads) such an exception fails its trial with its text, as a C++ fault does.
class FailureScope {
public:
    explicit FailureScope(PythonFailure& failure);
    ~FailureScope();
    FailureScope(const FailureScope&) = delete;
    FailureScope& operator=(const FailureScope&) = delete;

private:
    PythonFailure* previous_;
};
// The fault to throw into the trial for a Python exception raised in `where` (the GIL held).
PluginFault python_fault(py::error_already_set&& error, const std::string& where);

// A dict as the text of a TOML file (a config, a simulation profile): tables, arrays, strings,
// booleans, integers and reals; TypeError naming `argument` and the key for anything else.
std::string toml_text_of(py::handle mapping, const std::string& argument);

// Python integers as counts and seeds (None: nullopt): TypeError or ValueError naming `argument`.
std::optional<std::int64_t> integer_of(py::handle value, const std::string& argument, std::int64_t minimum);
std::uint64_t seed_of(py::handle value, const std::string& argument);
std::optional<double> optional_real(py::handle value, const std::string& argument);

}  // namespace mhb::python

// Values crossing between Python and the framework: numpy arrays as populations and boxes, Python
// scalars as plugin parameters, counts and seeds, and Python errors raised inside a trial.
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "framework/python/python_bindings.hpp"

namespace mhb::python {
namespace {

std::string type_name_of(py::handle value) { return py::str(py::type::handle_of(value).attr("__name__")); }

py::array as_array(py::handle x, const std::string& argument) {
    if (py::isinstance<py::array>(x)) return py::reinterpret_borrow<py::array>(x);
    try {
        return py::module_::import("numpy").attr("asarray")(x);
    } catch (py::error_already_set&) {
        throw py::type_error(fmt::format("{}: expects an array of real numbers, got {}", argument, type_name_of(x)));
    }
}

void require_real_dtype(const py::array& a, const std::string& argument) {
    const char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw py::type_error(fmt::format("{}: expects real numbers (float64 is used without a copy), got dtype {}", argument,
                                         std::string(py::str(a.dtype()))));
}

}  // namespace

std::optional<Eigen::Index> columns_of(py::handle x) {
    if (!py::isinstance<py::array>(x)) return std::nullopt;
    const auto a = py::reinterpret_borrow<py::array>(x);
    if (a.ndim() == 2) return static_cast<Eigen::Index>(a.shape(1));
    if (a.ndim() == 1) return static_cast<Eigen::Index>(a.shape(0));
    return std::nullopt;
}

Population::Population(py::handle x, const std::string& argument, Eigen::Index dimension, bool single_point_allowed) {
    array_ = as_array(x, argument);
    require_real_dtype(array_, argument);
    if (array_.ndim() == 1 && single_point_allowed) {
        single_point_ = true;
        count_ = 1;
        dimension_ = static_cast<Eigen::Index>(array_.shape(0));
    } else if (array_.ndim() == 2) {
        count_ = static_cast<Eigen::Index>(array_.shape(0));
        dimension_ = static_cast<Eigen::Index>(array_.shape(1));
    } else {
        throw py::value_error(fmt::format("{}: expects a 2-D array of shape (n, D){}, got {} dimension(s)", argument,
                                          single_point_allowed ? " or one point of shape (D,)" : "", array_.ndim()));
    }
    if (dimension >= 0 && dimension_ != dimension)
        throw py::value_error(fmt::format("{}: points have {} coordinate(s), the problem has dimension {}", argument,
                                          dimension_, dimension));
    in_place_ = py::array_t<double, py::array::c_style>::check_(array_);
    if (!in_place_) array_ = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array_);
    if (!array_) throw py::error_already_set();
    data_ = static_cast<const double*>(array_.data());
    const auto total = count_ * dimension_;
    for (Eigen::Index k = 0; k < total; ++k)
        if (!std::isfinite(data_[k]))
            throw py::value_error(fmt::format("{}: point {} has a coordinate that is not finite (x{} = {})", argument,
                                              k / dimension_, k % dimension_ + 1, data_[k]));
}

py::array_t<double> numpy_points(const Eigen::Ref<const Matrix>& x) {
    const auto n = x.cols(), d = x.rows();
    py::array_t<double> out({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(d)});
    double* to = out.mutable_data();
    for (Eigen::Index i = 0; i < n; ++i) std::copy(x.col(i).data(), x.col(i).data() + d, to + i * d);
    return out;
}

py::array_t<double> numpy_vector(const Eigen::Ref<const Vector>& v) {
    py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
    std::copy(v.data(), v.data() + v.size(), out.mutable_data());
    return out;
}

Bounds bounds_of(py::handle bounds, const std::string& argument) {
    if (bounds.is_none()) throw py::type_error(argument + ": expects (lower, upper) per variable, shape (D, 2); got None");
    const py::array a = as_array(bounds, argument);
    require_real_dtype(a, argument);
    if (a.ndim() != 2 || a.shape(1) != 2 || a.shape(0) < 1)
        throw py::value_error(fmt::format("{}: expects one (lower, upper) row per variable, shape (D, 2); got shape ({})",
                                          argument, fmt::join(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()), ", ")));
    const auto c = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
    const auto d = static_cast<Eigen::Index>(c.shape(0));
    Bounds box{Vector(d), Vector(d)};
    for (Eigen::Index j = 0; j < d; ++j) {
        box.lower[j] = c.at(j, 0);
        box.upper[j] = c.at(j, 1);
        if (!std::isfinite(box.lower[j]) || !std::isfinite(box.upper[j]))
            throw py::value_error(fmt::format("{}: row {} is ({}, {}); both bounds must be finite", argument, j, box.lower[j],
                                              box.upper[j]));
        if (box.lower[j] > box.upper[j])
            throw py::value_error(fmt::format("{}: row {} has lower {} > upper {}", argument, j, box.lower[j], box.upper[j]));
    }
    return box;
}

py::array_t<double> numpy_bounds(const Bounds& bounds) {
    const auto d = bounds.lower.size();
    py::array_t<double> out({static_cast<py::ssize_t>(d), py::ssize_t{2}});
    auto view = out.mutable_unchecked<2>();
    for (Eigen::Index j = 0; j < d; ++j) {
        view(j, 0) = bounds.lower[j];
        view(j, 1) = bounds.upper[j];
    }
    return out;
}

std::map<std::string, ParameterValue> parameter_values(py::handle options, const std::string& argument) {
    std::map<std::string, ParameterValue> values;
    if (options.is_none()) return values;
    if (!py::isinstance<py::dict>(options))
        throw py::type_error(fmt::format("{}: expects a dict of parameter values, got {}", argument, type_name_of(options)));
    for (const auto& [key, item] : py::reinterpret_borrow<py::dict>(options)) {
        if (!py::isinstance<py::str>(key))
            throw py::type_error(fmt::format("{}: parameter names are strings, got {}", argument, type_name_of(key)));
        const auto name = key.cast<std::string>();
        const auto field = fmt::format("{}['{}']", argument, name);
        py::handle value = item;
        py::object scalar;
        if (py::hasattr(value, "dtype") && py::hasattr(value, "item")) {  // a numpy scalar: its Python value
            scalar = value.attr("item")();
            value = scalar;
        }
        if (PyBool_Check(value.ptr())) {
            values[name] = value.cast<bool>();
        } else if (PyLong_Check(value.ptr())) {
            int overflow = 0;
            const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
            if (overflow != 0) throw py::value_error(field + ": integer out of the 64-bit range");
            values[name] = static_cast<std::int64_t>(v);
        } else if (PyFloat_Check(value.ptr())) {
            values[name] = value.cast<double>();
        } else if (py::isinstance<py::str>(value)) {
            values[name] = value.cast<std::string>();
        } else {
            throw py::type_error(fmt::format("{}: expects a bool, an integer, a real number or a string, got {}", field,
                                             type_name_of(value)));
        }
    }
    return values;
}

py::object python_value(const ParameterValue& value) {
    return std::visit([](const auto& v) -> py::object { return py::cast(v); }, value);
}

std::optional<std::int64_t> integer_of(py::handle value, const std::string& argument, std::int64_t minimum) {
    if (value.is_none()) return std::nullopt;
    if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr()))
        throw py::type_error(fmt::format("{}: expects an integer, got {}", argument, type_name_of(value)));
    const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(value.ptr()));
    if (!index) throw py::error_already_set();
    int overflow = 0;
    const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
    if (overflow != 0 || v < minimum)
        throw py::value_error(fmt::format("{}: expects an integer >= {}, got {}", argument, minimum, std::string(py::str(value))));
    return static_cast<std::int64_t>(v);
}

std::uint64_t seed_of(py::handle value, const std::string& argument) {
    if (PyBool_Check(value.ptr()) || !PyIndex_Check(value.ptr()))
        throw py::type_error(fmt::format("{}: expects an integer in [0, 2**64), got {}", argument, type_name_of(value)));
    const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(value.ptr()));
    if (!index) throw py::error_already_set();
    const unsigned long long v = PyLong_AsUnsignedLongLong(index.ptr());
    if (v == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {
        PyErr_Clear();
        throw py::value_error(fmt::format("{}: expects an integer in [0, 2**64), got {}", argument, std::string(py::str(value))));
    }
    return static_cast<std::uint64_t>(v);
}

std::optional<double> optional_real(py::handle value, const std::string& argument) {
    if (value.is_none()) return std::nullopt;
    if (PyBool_Check(value.ptr()) || !(PyFloat_Check(value.ptr()) || PyIndex_Check(value.ptr()) ||
                                        py::hasattr(value, "__float__")))
        throw py::type_error(fmt::format("{}: expects a real number, got {}", argument, type_name_of(value)));
    const double v = PyFloat_AsDouble(value.ptr());
    if (v == -1.0 && PyErr_Occurred()) throw py::error_already_set();
    if (std::isnan(v)) throw py::value_error(argument + ": expects a real number, got nan");
    return v;
}

namespace {
thread_local PythonFailure* failure_of_this_thread = nullptr;
}

FailureScope::FailureScope(PythonFailure& failure) : previous_(failure_of_this_thread) { failure_of_this_thread = &failure; }
FailureScope::~FailureScope() { failure_of_this_thread = previous_; }

PluginFault python_fault(py::error_already_set&& error, const std::string& where) {
    if (failure_of_this_thread) return failure_of_this_thread->keep(std::move(error), where);
    return PluginFault(where + " raised " + error.what());
}

PluginFault PythonFailure::keep(py::error_already_set&& error, const std::string& where) {
    const std::string text = error.what();
    std::lock_guard lock(mutex_);
    if (!error_) error_.emplace(std::move(error));
    return PluginFault(where + " raised " + text);
}

bool PythonFailure::kept() const {
    std::lock_guard lock(mutex_);
    return error_.has_value();
}

void PythonFailure::rethrow_if_kept() {
    std::optional<py::error_already_set> error;
    {
        std::lock_guard lock(mutex_);
        error.swap(error_);
    }
    if (error) throw *error;
}

}  // namespace mhb::python

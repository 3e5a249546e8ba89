// mhbench.InputError and mhbench.PluginFault: the C++ exceptions a call can end with, as Python
// exceptions. Bad values given from Python (an unknown name, a parameter out of range, a config
// that does not load) are InputError, a ValueError; a fault of a plugin during a run is PluginFault.
#include <Python.h>

#include "framework/python/python_bindings.hpp"
#include "framework/registry.hpp"

namespace mhb::python {
namespace {

// Created once and never released: the module's exception types live as long as the interpreter,
// and a static py::object would be released after it has finalised.
PyObject* input_error_type = nullptr;
PyObject* plugin_fault_type = nullptr;

void raise_input_error(const std::string& file, long line, const std::string& field, const std::string& message,
                       const std::string& full_text) {
    // Without a file the error concerns an argument of the call: "options['population']: must lie in [4, 10000]".
    const std::string text = file.empty() ? (field.empty() ? message : field + ": " + message) : full_text;
    py::object error = py::reinterpret_steal<py::object>(PyObject_CallFunction(input_error_type, "s", text.c_str()));
    if (!error) return;  // the call set its own error
    error.attr("file") = file.empty() ? py::object(py::none()) : py::object(py::str(file));
    error.attr("line") = line > 0 ? py::object(py::int_(line)) : py::object(py::none());
    error.attr("field") = field.empty() ? py::object(py::none()) : py::object(py::str(field));
    error.attr("reason") = py::str(message);
    PyErr_SetObject(input_error_type, error.ptr());
}

}  // namespace

void throw_input_error(const std::string& field, const std::string& message) {
    throw InputError("", 0, field, message);
}

void bind_errors(py::module_& m) {
    input_error_type = PyErr_NewExceptionWithDoc(
        "mhbench.InputError",
        "A value given to mhbench is wrong: an unknown name, a parameter out of its range, a config or a data file "
        "that does not load. Attributes: file and line (None when the error is in an argument of the call), field "
        "(the argument, parameter or config field, or None) and reason (the message without them).",
        PyExc_ValueError, nullptr);
    plugin_fault_type = PyErr_NewExceptionWithDoc(
        "mhbench.PluginFault",
        "An optimizer or a problem broke the framework's contract during a run (a NaN fitness, a candidate "
        "outside the box, a C++ exception): the run stopped.",
        PyExc_RuntimeError, nullptr);
    m.add_object("InputError", py::reinterpret_borrow<py::object>(input_error_type));
    m.add_object("PluginFault", py::reinterpret_borrow<py::object>(plugin_fault_type));

    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const InputError& e) {
            raise_input_error(e.file(), e.line(), e.field(), e.message(), e.what());
        } catch (const ParameterError& e) {
            raise_input_error("", 0, e.field(), e.message(), e.what());
        } catch (const UnknownPlugin& e) {
            raise_input_error("", 0, "", e.what(), e.what());
        } catch (const PluginFault& e) {
            PyErr_SetString(plugin_fault_type, e.what());
        }
    });
}

}  // namespace mhb::python

// mhbench.Problem and mhbench.evaluate: a registered problem evaluated on numpy points. The points
// are read in place (no copy of an (n, D) float64 C-contiguous array) and the GIL is released while
// the problem computes.
#include <memory>

#include <fmt/format.h>

#include "framework/python/python_bindings.hpp"
#include "framework/registry.hpp"

namespace mhb::python {
namespace {

// A registered problem made once, for many evaluations.
struct ProblemObject {
    std::string name;
    std::map<std::string, ParameterValue> values;
    std::unique_ptr<Problem> problem;
};

std::shared_ptr<ProblemObject> make_problem_object(const std::string& name, py::handle dimension, py::handle instance,
                                                   py::handle options) {
    const auto& entry = ProblemRegistry::instance().at(name, "problem");
    auto declares = [&](const std::string& parameter) {
        return std::any_of(entry.parameters.begin(), entry.parameters.end(),
                           [&](const ParameterSpec& p) { return p.name == parameter; });
    };
    auto object = std::make_shared<ProblemObject>();
    object->name = entry.name;
    object->values = parameter_values(options, "options");
    const auto d = integer_of(dimension, "dimension", 1);
    if (d && declares("dimension")) object->values["dimension"] = *d;
    const auto i = integer_of(instance, "instance", 1);
    if (i) {
        if (!declares("instance")) throw_input_error("instance", fmt::format("the problem {} has no instances", entry.name));
        object->values["instance"] = *i;
    }
    try {
        object->problem = make_problem(entry.name, object->values);
    } catch (const ParameterError& e) {
        const bool argument = (e.field() == "dimension" && d) || (e.field() == "instance" && i);
        throw_input_error(argument ? e.field() : fmt::format("options['{}']", e.field()), e.message());
    }
    if (d && object->problem->dimension() != *d)
        throw_input_error("dimension", fmt::format("the problem {} has a fixed dimension of {} (got {})", entry.name,
                                                   object->problem->dimension(), *d));
    return object;
}

// f at each point of x: n values, or one float for a single point of shape (D,).
py::object evaluate_points(const ProblemObject& object, py::handle x) {
    const Problem& problem = *object.problem;
    const Population population(x, "X", problem.dimension(), true);
    py::array_t<double> f(static_cast<py::ssize_t>(population.count()));
    Eigen::Map<Vector> values(f.mutable_data(), population.count());
    if (population.count() > 0) {
        py::gil_scoped_release release;
        problem.evaluate(population.points(), values);
    }
    if (population.single_point()) return py::float_(values[0]);
    return f;
}

}  // namespace

void bind_problems(py::module_& m) {
    py::class_<ProblemObject, std::shared_ptr<ProblemObject>>(m, "Problem",
        "A registered problem, made once for many evaluations: Problem('bbob_f3', dimension=10, instance=2). "
        "dimension and instance apply when the problem declares them; options holds its other parameters.")
        .def(py::init(&make_problem_object), py::arg("name"), py::arg("dimension") = py::none(),
             py::arg("instance") = py::none(), py::arg("options") = py::none())
        .def_readonly("name", &ProblemObject::name)
        .def_property_readonly("parameters", [](const ProblemObject& o) {
            py::dict d;
            for (const auto& [k, v] : o.values) d[py::str(k)] = python_value(v);
            return d;
        }, "the parameter values given (the others have their defaults)")
        .def_property_readonly("dimension", [](const ProblemObject& o) { return o.problem->dimension(); })
        .def_property_readonly("bounds", [](const ProblemObject& o) { return numpy_bounds(o.problem->bounds()); },
                               "the box, one (lower, upper) row per variable: shape (D, 2)")
        .def_property_readonly("variable_names", [](const ProblemObject& o) { return o.problem->parameter_names(); })
        .def_property_readonly("optimum", [](const ProblemObject& o) -> py::object {
            const auto& v = o.problem->truth().optimum_value;
            return v ? py::object(py::float_(*v)) : py::object(py::none());
        }, "the global minimum of the objective, or None when it is not known")
        .def_property_readonly("description", [](const ProblemObject& o) { return o.problem->describe(); })
        .def("evaluate", &evaluate_points, py::arg("X"),
             "f at each row of X, an (n, D) array (read in place when float64 and C-contiguous): n values. "
             "A 1-D X of length D is one point and gives a float.")
        .def("__call__", &evaluate_points, py::arg("X"))
        .def("__repr__", [](const ProblemObject& o) {
            return fmt::format("mhbench.Problem('{}', dimension={})", o.name, o.problem->dimension());
        });

    m.def(
        "evaluate",
        [](py::object problem, py::object x, py::object instance, py::object options) -> py::object {
            if (py::isinstance<ProblemObject>(problem)) {
                if (!instance.is_none() || !options.is_none())
                    throw py::value_error("instance, options: given with a Problem object, which already has them");
                return evaluate_points(problem.cast<const ProblemObject&>(), x);
            }
            if (!py::isinstance<py::str>(problem))
                throw py::type_error("problem: expects a registered problem's name or an mhbench.Problem, got " +
                                     std::string(py::str(py::type::handle_of(problem).attr("__name__"))));
            if (!py::isinstance<py::array>(x)) x = py::module_::import("numpy").attr("asarray")(x);
            const auto columns = columns_of(x);
            const auto object = make_problem_object(problem.cast<std::string>(),
                                                    columns ? py::object(py::int_(*columns)) : py::object(py::none()),
                                                    instance, options);
            return evaluate_points(*object, x);
        },
        py::arg("problem"), py::arg("X"), py::arg("instance") = py::none(), py::arg("options") = py::none(),
        "f of a registered problem at each row of X, an (n, D) array: n values (a 1-D X of length D gives one float). "
        "The problem is made with dimension D when it declares a dimension.");
}

}  // namespace mhb::python

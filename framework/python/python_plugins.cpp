// mhbench.register_optimizer / register_problem: an optimizer or a problem written in Python, in the
// same registries as the C++ ones, so that minimize, run and TOML experiments use it by name. Each
// call into Python takes the GIL for itself; trials on other threads wait for it only then.
#include <limits>
#include <memory>

#include <fmt/format.h>

#include "framework/python/python_bindings.hpp"
#include "framework/registry.hpp"

namespace mhb::python {
namespace {

// A Python object held by C++ code that may release it on any thread: the GIL is taken to release it.
class HeldObject {
public:
    explicit HeldObject(py::object object) : object_(std::move(object)) {}
    ~HeldObject() {
        if (!Py_IsInitialized()) {
            object_.release();  // the interpreter is gone: nothing left to release it into
            return;
        }
        py::gil_scoped_acquire gil;
        object_ = py::object();
    }
    HeldObject(const HeldObject&) = delete;
    HeldObject& operator=(const HeldObject&) = delete;
    const py::object& get() const { return object_; }

private:
    py::object object_;
};

std::string type_name_of(py::handle value) { return py::str(py::type::handle_of(value).attr("__name__")); }

// Declared parameters from {name: default}: the type of the default, no range.
std::vector<ParameterSpec> parameter_specs(py::handle parameters) {
    std::vector<ParameterSpec> specs;
    constexpr auto lowest = std::numeric_limits<std::int64_t>::min(), highest = std::numeric_limits<std::int64_t>::max();
    constexpr auto infinity = std::numeric_limits<double>::infinity();
    for (const auto& [name, value] : parameter_values(parameters, "parameters")) {
        std::visit(
            [&, &name = name](const auto& v) {
                using T = std::decay_t<decltype(v)>;
                if constexpr (std::is_same_v<T, bool>) specs.push_back(ParameterSpec::boolean(name, v, "declared in Python"));
                else if constexpr (std::is_same_v<T, std::int64_t>)
                    specs.push_back(ParameterSpec::integer(name, v, lowest, highest, "declared in Python"));
                else if constexpr (std::is_same_v<T, double>)
                    specs.push_back(ParameterSpec::real(name, v, -infinity, infinity, "declared in Python"));
                else specs.push_back(ParameterSpec::text(name, v, "declared in Python"));
            },
            value);
    }
    return specs;
}

py::dict keyword_arguments(const ParameterSet& parameters) {
    py::dict kwargs;
    for (const auto& [name, value] : parameters.values()) kwargs[py::str(name)] = python_value(value);
    return kwargs;
}

// An instance of a registered Python problem class: bounds (shape (D, 2)), evaluate(X) -> n values,
// and optionally optimum and variable_names.
class PythonProblem final : public Problem {
public:
    PythonProblem(py::object instance, std::string name) : instance_(std::make_shared<HeldObject>(std::move(instance))), name_(std::move(name)) {
        const py::object& self = instance_->get();
        if (!py::hasattr(self, "bounds") || !py::hasattr(self, "evaluate"))
            throw py::type_error(fmt::format("problem {}: a problem class has bounds (shape (D, 2)) and evaluate(X)", name_));
        py::object bounds = self.attr("bounds");
        if (PyCallable_Check(bounds.ptr())) bounds = bounds();
        const Bounds box = bounds_of(bounds, fmt::format("problem {}: bounds", name_));
        std::vector<std::string> names;
        if (py::hasattr(self, "variable_names") && !self.attr("variable_names").is_none()) {
            names = self.attr("variable_names").cast<std::vector<std::string>>();
            if (static_cast<Eigen::Index>(names.size()) != box.lower.size())
                throw py::value_error(fmt::format("problem {}: {} variable_names for dimension {}", name_, names.size(), box.lower.size()));
        }
        set_domain(box.lower, box.upper, names);
        if (py::hasattr(self, "optimum") && !self.attr("optimum").is_none())
            truth_.optimum_value = self.attr("optimum").cast<double>();
    }

    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        py::gil_scoped_acquire gil;
        try {
            const py::object result = instance_->get().attr("evaluate")(numpy_points(x));
            const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(result);
            if (!values || values.size() != x.cols()) {
                PyErr_SetString(PyExc_ValueError, fmt::format("problem {}: evaluate must return {} real numbers, one per row "
                                                              "of X; returned {}",
                                                              name_, x.cols(), type_name_of(result)).c_str());
                throw py::error_already_set();
            }
            std::copy(values.data(), values.data() + values.size(), f.data());
        } catch (py::error_already_set& e) {
            throw python_fault(std::move(e), "problem " + name_);
        }
    }

private:
    std::shared_ptr<HeldObject> instance_;
    std::string name_;
};

// What a Python optimizer is handed during one call; refused once the call has returned, when the
// trial's evaluator and generator may be gone.
struct EvaluatorView {
    Evaluator* evaluator = nullptr;
    Evaluator& get() const {
        if (!evaluator) throw std::runtime_error("this evaluator belonged to a call that has returned");
        return *evaluator;
    }
};
struct RandomView {
    Rng* rng = nullptr;
    Rng& get() const {
        if (!rng) throw std::runtime_error("this generator belonged to a call that has returned");
        return *rng;
    }
};
struct ProgressView {
    Progress progress;
};

// Lends `evaluator` and `rng` to Python for one call and takes them back whatever happens.
class Lending {
public:
    Lending(Evaluator& evaluator, Rng& rng)
        : evaluator_(std::make_shared<EvaluatorView>(EvaluatorView{&evaluator})), rng_(std::make_shared<RandomView>(RandomView{&rng})) {}
    ~Lending() {
        evaluator_->evaluator = nullptr;
        rng_->rng = nullptr;
    }
    py::object evaluator() const { return py::cast(evaluator_); }
    py::object rng() const { return py::cast(rng_); }

private:
    std::shared_ptr<EvaluatorView> evaluator_;
    std::shared_ptr<RandomView> rng_;
};

// An instance of a registered Python optimizer class: initialize(evaluator, rng) and
// iterate(progress, evaluator, rng).
class PythonOptimizer final : public Optimizer {
public:
    PythonOptimizer(py::object instance, std::string name) : instance_(std::make_shared<HeldObject>(std::move(instance))), name_(std::move(name)) {
        for (const char* method : {"initialize", "iterate"})
            if (!py::hasattr(instance_->get(), method))
                throw py::type_error(fmt::format("optimizer {}: an optimizer class has initialize(evaluator, rng) and "
                                                 "iterate(progress, evaluator, rng)", name_));
    }

    void initialize(Evaluator& evaluator, Rng& rng) override {
        py::gil_scoped_acquire gil;
        try {
            const Lending lent(evaluator, rng);
            instance_->get().attr("initialize")(lent.evaluator(), lent.rng());
        } catch (py::error_already_set& e) {
            throw python_fault(std::move(e), "optimizer " + name_);
        }
    }

    void iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) override {
        py::gil_scoped_acquire gil;
        try {
            const Lending lent(evaluator, rng);
            instance_->get().attr("iterate")(ProgressView{progress}, lent.evaluator(), lent.rng());
        } catch (py::error_already_set& e) {
            throw python_fault(std::move(e), "optimizer " + name_);
        }
    }

private:
    std::shared_ptr<HeldObject> instance_;
    std::string name_;
};

// Numbers drawn from the trial's generator in C order, so that a Python optimizer's run is fixed by its seed.
template <class Draw>
py::object draws(py::handle size, Draw&& draw) {
    if (size.is_none()) return py::float_(draw());
    std::vector<py::ssize_t> shape;
    if (PyIndex_Check(size.ptr())) shape.push_back(static_cast<py::ssize_t>(*integer_of(size, "size", 0)));
    else
        for (const auto& extent : size) shape.push_back(static_cast<py::ssize_t>(*integer_of(extent, "size", 0)));
    py::array_t<double> out(shape);
    double* to = out.mutable_data();
    for (py::ssize_t k = 0; k < out.size(); ++k) to[k] = draw();
    return out;
}

template <class Factory>
void check_free(const std::string& name, const std::string& kind) {
    if (const auto* entry = Registry<Factory>::instance().find(name))
        throw_input_error("name", fmt::format("the {} name '{}' is taken ({}); choose another", kind, entry->name,
                                              Registry<Factory>::instance().origin(entry->name)));
}

// Registry entries hold Python classes: they are removed before the interpreter finalises.
template <class Factory>
void remove_at_exit(const std::string& name) {
    py::module_::import("atexit").attr("register")(py::cpp_function([name] { Registry<Factory>::instance().remove(name); }));
}

std::string summary_of(py::handle cls, py::handle summary) {
    if (!summary.is_none()) return summary.cast<std::string>();
    const py::object doc = cls.attr("__doc__");
    if (doc.is_none()) return "written in Python";
    const auto text = doc.cast<std::string>();
    const auto start = text.find_first_not_of(" \n\t");
    if (start == std::string::npos) return "written in Python";
    return text.substr(start, text.find('\n', start) - start);
}

// Registers `cls` as a plugin of the registry of `Factory`; each instance is wrapped in `Wrapper`
// (PythonProblem or PythonOptimizer). The factories of both kinds take the parameter set first.
template <class Factory, class Wrapper>
void register_python_class(const std::string& kind, const std::string& name, py::object cls, py::handle summary,
                           py::handle parameters) {
    if (!PyCallable_Check(cls.ptr())) throw py::type_error("cls: expects a class, got " + type_name_of(cls));
    check_free<Factory>(name, kind);
    auto held = std::make_shared<HeldObject>(cls);
    const std::string where = kind + " " + name;
    Registry<Factory>::instance().add(
        {name, summary_of(cls, summary), parameter_specs(parameters),
         [held, name, where](const ParameterSet& values, const auto&...) -> typename Factory::result_type {
             py::gil_scoped_acquire gil;
             try {
                 return std::make_unique<Wrapper>(held->get()(**keyword_arguments(values)), name);
             } catch (py::error_already_set& e) {
                 throw python_fault(std::move(e), where);
             } catch (const py::builtin_exception& e) {
                 throw PluginFault(e.what());
             }
         }});
    remove_at_exit<Factory>(name);
}

}  // namespace

void bind_python_plugins(py::module_& m) {
    py::class_<EvaluatorView, std::shared_ptr<EvaluatorView>>(m, "Evaluator",
        "What a Python optimizer evaluates through: it counts, enforces the budget and keeps the best point")
        .def("evaluate", [](const EvaluatorView& view, py::handle x) {
            Evaluator& evaluator = view.get();
            const Population population(x, "X", evaluator.dimension(), false);
            py::array_t<double> f(static_cast<py::ssize_t>(population.count()));
            Eigen::Map<Vector> values(f.mutable_data(), population.count());
            {
                py::gil_scoped_release release;
                evaluator.evaluate(population.points(), values);
            }
            return f;
        }, py::arg("X"), "f at each row of X, (n, D): n values; rows past the budget are not evaluated and get inf")
        .def_property_readonly("dimension", [](const EvaluatorView& v) { return v.get().dimension(); })
        .def_property_readonly("bounds", [](const EvaluatorView& v) { return numpy_bounds(v.get().bounds()); })
        .def_property_readonly("evaluations", [](const EvaluatorView& v) { return v.get().evaluations(); })
        .def_property_readonly("remaining", [](const EvaluatorView& v) { return v.get().remaining(); })
        .def_property_readonly("exhausted", [](const EvaluatorView& v) { return v.get().exhausted(); })
        .def_property_readonly("best_f", [](const EvaluatorView& v) { return v.get().best_fitness(); })
        .def_property_readonly("best_x", [](const EvaluatorView& v) { return numpy_vector(v.get().best_position()); });

    py::class_<RandomView, std::shared_ptr<RandomView>>(m, "Random",
        "The trial's random generator (xoshiro256++ seeded by the trial): arrays are filled in C order")
        .def("uniform", [](const RandomView& v, double low, double high, py::handle size) {
            Rng& rng = v.get();
            return draws(size, [&] { return rng.uniform(low, high); });
        }, py::arg("low") = 0.0, py::arg("high") = 1.0, py::arg("size") = py::none())
        .def("normal", [](const RandomView& v, double mean, double sd, py::handle size) {
            Rng& rng = v.get();
            return draws(size, [&] { return rng.normal(mean, sd); });
        }, py::arg("mean") = 0.0, py::arg("sd") = 1.0, py::arg("size") = py::none())
        .def("below", [](const RandomView& v, std::uint64_t n) {
            if (n == 0) throw py::value_error("n: expects an integer >= 1");
            return v.get().below(n);
        }, py::arg("n"), "a uniform integer in [0, n)");

    py::class_<ProgressView>(m, "Progress", "Where the run stands when an iteration starts")
        .def_property_readonly("iteration", [](const ProgressView& p) { return p.progress.iteration; })
        .def_property_readonly("evaluations", [](const ProgressView& p) { return p.progress.evaluations; })
        .def("fraction", [](const ProgressView& p, std::int64_t offset) { return p.progress.fraction(offset); },
             py::arg("offset") = 0, "the share of the budget used, in [0, 1] (t/T)");

    m.def("register_problem", [](const std::string& name, py::object cls, py::handle summary, py::handle parameters) {
        register_python_class<ProblemFactory, PythonProblem>("problem", name, std::move(cls), summary, parameters);
    }, py::arg("name"), py::arg("cls"), py::arg("summary"), py::arg("parameters"));
    m.def("register_optimizer", [](const std::string& name, py::object cls, py::handle summary, py::handle parameters) {
        register_python_class<OptimizerFactory, PythonOptimizer>("optimizer", name, std::move(cls), summary, parameters);
    }, py::arg("name"), py::arg("cls"), py::arg("summary"), py::arg("parameters"));
}

}  // namespace mhb::python

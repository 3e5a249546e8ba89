// mhbench._mhbench.minimize: one run of a registered optimizer on a Python objective or a registered
// problem. The run is the command line's trial (framework/trial.cpp) with the same seed, so the same
// settings give the same result to the last bit; stopping on a target, a time or a callback is asked
// of the trial after each iteration.
#include <chrono>
#include <memory>

#include <fmt/format.h>

#include "framework/python/python_bindings.hpp"
#include "framework/registry.hpp"
#include "framework/trial.hpp"

namespace mhb::python {
namespace {

// fun(X, *args) on an (n, D) array, returning n values; or, with batch=False, fun(x, *args) once per
// point, returning a number. The GIL is taken for the call only.
class PythonObjective final : public Problem {
public:
    PythonObjective(py::object fun, py::tuple args, bool batch, const Bounds& box, PythonFailure& failure)
        : fun_(std::move(fun)), args_(std::move(args)), batch_(batch), failure_(failure) {
        set_domain(box.lower, box.upper);
    }

    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        py::gil_scoped_acquire gil;
        try {
            if (batch_) evaluate_batch(x, f);
            else evaluate_one_by_one(x, f);
        } catch (py::error_already_set& e) {
            throw failure_.keep(std::move(e), "fun");
        }
    }

private:
    // A Python exception raised where the objective's output is checked, so that it reaches the
    // caller as an exception of the objective would.
    [[noreturn]] static void raise(PyObject* type, const std::string& message) {
        PyErr_SetString(type, message.c_str());
        throw py::error_already_set();
    }

    void evaluate_batch(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const {
        // A new array per call, not a view of the optimiser's population: fun may keep it.
        const py::object result = fun_(numpy_points(x), *args_);
        const auto values = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(result);
        if (!values)
            raise(PyExc_TypeError, fmt::format("fun: must return {} real numbers, one per row of X; returned {}", x.cols(),
                                               std::string(py::str(py::type::handle_of(result).attr("__name__")))));
        if (values.size() != x.cols())
            raise(PyExc_ValueError,
                  fmt::format("fun: returned {} value(s) for {} points (an (n, D) array gives n values; with batch=False "
                              "fun is called with one point at a time)",
                              values.size(), x.cols()));
        std::copy(values.data(), values.data() + values.size(), f.data());
    }

    void evaluate_one_by_one(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const {
        for (Eigen::Index i = 0; i < x.cols(); ++i) {
            const py::object result = fun_(numpy_vector(x.col(i)), *args_);
            const double v = PyFloat_AsDouble(result.ptr());
            if (v == -1.0 && PyErr_Occurred()) {
                PyErr_Clear();
                raise(PyExc_TypeError, fmt::format("fun: with batch=False must return one real number; returned {}",
                                                   std::string(py::str(py::type::handle_of(result).attr("__name__")))));
            }
            f[i] = v;
        }
    }

    py::object fun_;
    py::tuple args_;
    bool batch_;
    PythonFailure& failure_;
};

// What a callback sees after initialisation (iteration 0) and after each iteration.
struct IterationState {
    std::int64_t iteration;
    std::int64_t evaluations;
    double f;
    py::array_t<double> x;
};

std::unique_ptr<Problem> problem_of(py::handle fun, py::handle bounds, py::handle args, bool batch,
                                    py::handle problem_options, PythonFailure& failure) {
    if (py::isinstance<py::str>(fun)) {
        if (!args.is_none() && py::len(args) > 0) throw py::value_error("args: only for a Python fun, not a problem's name");
        const auto& entry = ProblemRegistry::instance().at(fun.cast<std::string>(), "problem");
        std::unique_ptr<Problem> problem;
        try {
            problem = make_problem(entry.name, parameter_values(problem_options, "problem_options"));
        } catch (const ParameterError& e) {
            throw_input_error(fmt::format("problem_options['{}']", e.field()), e.message());
        }
        if (!bounds.is_none()) {
            const Bounds box = bounds_of(bounds, "bounds");
            if (box.lower.size() != problem->dimension())
                throw py::value_error(fmt::format("bounds: {} rows for the problem {} of dimension {}", box.lower.size(),
                                                  entry.name, problem->dimension()));
            problem->override_bounds(box.lower, box.upper);
        }
        return problem;
    }
    if (!PyCallable_Check(fun.ptr()))
        throw py::type_error("fun: expects a callable or a registered problem's name, got " +
                             std::string(py::str(py::type::handle_of(fun).attr("__name__"))));
    if (!problem_options.is_none()) throw py::value_error("problem_options: only for a problem given by name");
    py::tuple extra;
    if (!args.is_none()) {
        if (!py::isinstance<py::tuple>(args) && !py::isinstance<py::list>(args))
            throw py::type_error("args: expects a tuple of extra arguments for fun, got " +
                                 std::string(py::str(py::type::handle_of(args).attr("__name__"))));
        extra = py::tuple(py::reinterpret_borrow<py::object>(args));
    }
    return std::make_unique<PythonObjective>(py::reinterpret_borrow<py::object>(fun), extra, batch, bounds_of(bounds, "bounds"),
                                             failure);
}

py::dict minimize(py::handle optimizer_name, py::handle fun, py::handle bounds, py::handle budget, py::handle iterations,
                  py::handle seed, py::handle options, bool batch, py::handle callback, py::handle args, py::handle target,
                  py::handle max_time, py::handle problem_options) {
    if (!py::isinstance<py::str>(optimizer_name))
        throw py::type_error("optimizer: expects a registered optimizer's name, got " +
                             std::string(py::str(py::type::handle_of(optimizer_name).attr("__name__"))));
    const auto& entry = OptimizerRegistry::instance().at(optimizer_name.cast<std::string>(), "optimizer");
    Budget limit;
    limit.max_evaluations = integer_of(budget, "budget", 1).value_or(0);
    limit.max_iterations = integer_of(iterations, "iterations", 1).value_or(0);
    if (limit.max_evaluations == 0 && limit.max_iterations == 0)
        throw py::value_error("budget: give budget= (evaluations) or iterations= (or both); the run needs a limit");
    const auto stop_at = optional_real(target, "target");
    const auto seconds = optional_real(max_time, "max_time");
    if (seconds && *seconds <= 0) throw py::value_error("max_time: expects a positive number of seconds");
    if (!callback.is_none() && !PyCallable_Check(callback.ptr())) throw py::type_error("callback: expects a callable or None");

    PythonFailure failure;
    std::unique_ptr<Optimizer> optimizer;
    try {
        optimizer = make_optimizer(entry.name, parameter_values(options, "options"));
    } catch (const ParameterError& e) {
        throw_input_error(fmt::format("options['{}']", e.field()), e.message());
    }
    const auto problem = problem_of(fun, bounds, args, batch, problem_options, failure);

    TrialSetup setup;
    setup.budget = limit;
    setup.seed = seed_of(seed, "seed");
    std::string stopped_by;
    const auto start = std::chrono::steady_clock::now();
    const py::object user_callback = py::reinterpret_borrow<py::object>(callback);
    setup.stop = [&](const Evaluator& evaluator, std::int64_t iteration) {
        py::gil_scoped_acquire gil;
        try {
            // A Ctrl-C while C++ code runs is seen here, between iterations.
            if (PyErr_CheckSignals() != 0) throw py::error_already_set();
            if (!user_callback.is_none()) {
                const auto state = py::cast(IterationState{iteration, evaluator.evaluations(), evaluator.best_fitness(),
                                                           numpy_vector(evaluator.best_position())});
                if (PyObject_IsTrue(user_callback(state).ptr()) == 1) {
                    stopped_by = "callback";
                    return true;
                }
            }
        } catch (py::error_already_set& e) {
            throw failure.keep(std::move(e), "callback");
        }
        if (stop_at && evaluator.best_fitness() <= *stop_at) {
            stopped_by = "target";
            return true;
        }
        if (seconds && std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >= *seconds) {
            stopped_by = "time";
            return true;
        }
        return false;
    };

    TrialRecord record;
    {
        const FailureScope scope(failure);
        py::gil_scoped_release release;
        record = run_trial(*optimizer, *problem, setup);
    }
    failure.rethrow_if_kept();
    if (!record.ok) throw PluginFault(record.error);
    if (stopped_by.empty())
        stopped_by = limit.max_evaluations > 0 && record.evaluations >= limit.max_evaluations ? "budget" : "iterations";

    py::dict out;
    out["x"] = numpy_vector(record.best_position);
    out["f"] = record.best_fitness;
    out["history"] = py::array_t<double>(static_cast<py::ssize_t>(record.trace_best.size()), record.trace_best.data());
    out["history_evaluations"] =
        py::array_t<std::int64_t>(static_cast<py::ssize_t>(record.trace_evaluations.size()), record.trace_evaluations.data());
    out["evaluations"] = record.evaluations;
    out["iterations"] = record.iterations;
    out["seconds"] = record.seconds;
    out["seed"] = setup.seed;
    out["stop"] = stopped_by;
    out["optimizer"] = entry.name;
    return out;
}

}  // namespace

void bind_minimize(py::module_& m) {
    py::class_<IterationState>(m, "IterationState", "What a minimize callback sees after each iteration")
        .def_readonly("iteration", &IterationState::iteration, "0 after initialisation, then 1, 2, ...")
        .def_readonly("evaluations", &IterationState::evaluations, "evaluations so far")
        .def_readonly("f", &IterationState::f, "best value so far")
        .def_readonly("x", &IterationState::x, "best point so far")
        .def("__repr__", [](const IterationState& s) {
            return fmt::format("IterationState(iteration={}, evaluations={}, f={:.17g})", s.iteration, s.evaluations, s.f);
        });
    m.def("minimize", &minimize, py::arg("optimizer"), py::arg("fun"), py::arg("bounds"), py::arg("budget"),
          py::arg("iterations"), py::arg("seed"), py::arg("options"), py::arg("batch"), py::arg("callback"), py::arg("args"),
          py::arg("target"), py::arg("max_time"), py::arg("problem_options"));
}

}  // namespace mhb::python

// mhbench._mhbench.run: an experiment from its TOML file or from a dict of the same content, run as
// `mhbench run` runs it (the same seeds, results.jsonl, table.md, table.csv, report.html), returned as
// columns for numpy. Trials of Python-defined plugins take the GIL for their calls only.
#include <sstream>
#include <variant>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "framework/experiment_report.hpp"
#include "framework/experiment_runner.hpp"
#include "framework/plots.hpp"
#include "framework/python/python_bindings.hpp"
#include "framework/report_tables.hpp"

namespace mhb::python {
namespace {

namespace fs = std::filesystem;
using namespace pybind11::literals;

using TomlValue = std::variant<toml::table, toml::array, bool, std::int64_t, double, std::string>;

// A Python value as TOML, for a config given as a dict: tables, arrays, strings, booleans, integers
// and reals, as a TOML file holds them.
TomlValue toml_value_of(py::handle value, const std::string& argument, const std::string& path) {
    if (py::isinstance<py::dict>(value)) {
        toml::table table;
        for (const auto& [key, item] : py::reinterpret_borrow<py::dict>(value)) {
            if (!py::isinstance<py::str>(key)) throw py::type_error(fmt::format("{}: {}: keys are strings", argument, path));
            const auto name = key.cast<std::string>();
            std::visit([&](auto&& v) { table.insert_or_assign(name, std::move(v)); },
                       toml_value_of(item, argument, path.empty() ? name : path + "." + name));
        }
        return table;
    }
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
        toml::array array;
        std::size_t i = 0;
        for (const auto& item : value)
            std::visit([&](auto&& v) { array.push_back(std::move(v)); },
                       toml_value_of(item, argument, fmt::format("{}[{}]", path, i++)));
        return array;
    }
    if (PyBool_Check(value.ptr())) return value.cast<bool>();
    if (PyLong_Check(value.ptr())) return value.cast<std::int64_t>();
    if (PyFloat_Check(value.ptr())) return value.cast<double>();
    if (py::isinstance<py::str>(value)) return value.cast<std::string>();
    if (py::hasattr(value, "__fspath__")) return py::str(value.attr("__fspath__")()).cast<std::string>();
    if (py::hasattr(value, "dtype") && py::hasattr(value, "item")) return toml_value_of(value.attr("item")(), argument, path);
    throw py::type_error(fmt::format("{}: {}: a TOML value is a dict, a list, a string, a bool or a number; got {}", argument,
                                     path, std::string(py::str(py::type::handle_of(value).attr("__name__")))));
}

}  // namespace

std::string toml_text_of(py::handle mapping, const std::string& argument) {
    if (!py::isinstance<py::dict>(mapping))
        throw py::type_error(argument + ": expects a dict, got " + std::string(py::str(py::type::handle_of(mapping).attr("__name__"))));
    std::ostringstream text;
    text << std::get<toml::table>(toml_value_of(mapping, argument, "")) << "\n";
    return text.str();
}

namespace {

ExperimentSpec experiment_of(py::handle config) {
    if (py::isinstance<py::dict>(config)) {
        // Relative paths in it (output, data files) are relative to the working directory.
        return parse_experiment(toml_text_of(config, "config"), fs::path("<dict>"));
    }
    if (py::isinstance<py::str>(config) || py::hasattr(config, "__fspath__"))
        return load_experiment(fs::path(py::str(py::module_::import("os").attr("fspath")(config)).cast<std::string>()));
    throw py::type_error("config: expects the path of an experiment's TOML file or a dict of the same content, got " +
                         std::string(py::str(py::type::handle_of(config).attr("__name__"))));
}

// A table's cells by column: float64 when every cell of the column is a number or blank (NaN), text otherwise.
py::dict table_columns(const Table& table) {
    py::dict out;
    const auto& rows = table.rows();
    for (std::size_t c = 0; c < table.columns().size(); ++c) {
        std::vector<double> numbers;
        bool numeric = true;
        for (const auto& row : rows) {
            const auto& cell = row[c];
            if (cell.blank || cell.text.empty()) {
                numbers.push_back(std::numeric_limits<double>::quiet_NaN());
                continue;
            }
            std::size_t used = 0;
            try {
                numbers.push_back(std::stod(cell.text, &used));
            } catch (const std::exception&) {
                used = 0;
            }
            if (used != cell.text.size()) {
                numeric = false;
                break;
            }
        }
        const auto key = py::str(table.columns()[c].label());
        if (numeric) {
            out[key] = py::array_t<double>(static_cast<py::ssize_t>(numbers.size()), numbers.data());
        } else {
            py::list texts;
            for (const auto& row : rows) texts.append(row[c].text);
            out[key] = py::module_::import("numpy").attr("array")(texts, "dtype"_a = "str");
        }
    }
    return out;
}

py::dict trial_columns(const std::vector<TrialRecord>& records) {
    const auto n = static_cast<py::ssize_t>(records.size());
    py::list optimizer, problem, error, position;
    py::array_t<std::int64_t> trial(n), evaluations(n), iterations(n);
    py::array_t<std::uint64_t> seed(n);
    py::array_t<bool> ok(n);
    py::array_t<double> best(n), seconds(n);
    for (py::ssize_t i = 0; i < n; ++i) {
        const auto& r = records[static_cast<std::size_t>(i)];
        optimizer.append(r.optimizer);
        problem.append(r.problem);
        error.append(r.error);
        position.append(numpy_vector(r.best_position));
        trial.mutable_at(i) = r.trial;
        seed.mutable_at(i) = r.seed;
        ok.mutable_at(i) = r.ok;
        best.mutable_at(i) = r.best_fitness;
        evaluations.mutable_at(i) = r.evaluations;
        iterations.mutable_at(i) = r.iterations;
        seconds.mutable_at(i) = r.seconds;
    }
    const auto numpy = py::module_::import("numpy");
    py::dict out;
    out["optimizer"] = numpy.attr("array")(optimizer, "dtype"_a = "str");
    out["problem"] = numpy.attr("array")(problem, "dtype"_a = "str");
    out["trial"] = trial;
    out["seed"] = seed;
    out["ok"] = ok;
    out["best_fitness"] = best;
    out["evaluations"] = evaluations;
    out["iterations"] = iterations;
    out["seconds"] = seconds;
    out["error"] = numpy.attr("array")(error, "dtype"_a = "str");
    // Problems of different dimensions share the column: an object array of 1-D arrays.
    py::array positions = numpy.attr("empty")(n, "dtype"_a = "object");
    for (py::ssize_t i = 0; i < n; ++i) positions.attr("__setitem__")(i, position[static_cast<std::size_t>(i)]);
    out["best_position"] = positions;
    return out;
}

py::dict run(py::handle config, py::handle threads, py::handle out, bool resume, bool plots) {
    const ExperimentSpec spec = experiment_of(config);
    RunOptions options;
    options.threads = static_cast<int>(integer_of(threads, "threads", 1).value_or(0));
    options.resume = resume;
    options.progress = false;
    if (!out.is_none()) options.output = fs::path(py::str(py::module_::import("os").attr("fspath")(out)).cast<std::string>());

    RunSummary summary;
    LoadedResults loaded;
    ExperimentInfo info;
    std::vector<std::string> notes;
    {
        py::gil_scoped_release release;
        summary = run_experiment(spec, options);
        info = read_experiment_info(summary.output);
        loaded = read_results(summary.output / "results.jsonl");
        const Document tables = write_tables(summary.output, info, loaded.records);
        ExperimentPlots drawn;
        drawn.absent_because = "No plots: the run from Python did not draw them (mhbench.run(..., plots=True) does).";
        if (plots && info.plots) {
            const auto outcome = write_plots(summary.output, info, loaded.records);
            drawn.images = outcome.images;
            notes = outcome.notes;
            if (!outcome.notes.empty()) drawn.absent_because = "No plots: " + outcome.notes.front() + ".";
        }
        write_experiment_report(summary.output, info, tables, drawn);
    }
    notes.insert(notes.begin(), summary.notes.begin(), summary.notes.end());
    notes.insert(notes.end(), loaded.notes.begin(), loaded.notes.end());

    py::dict result;
    result["output"] = summary.output.string();
    result["name"] = info.name;
    result["trials"] = trial_columns(loaded.records);
    result["table"] = table_columns(results_table(info, loaded.records));
    result["ran"] = summary.ran;
    result["skipped"] = summary.skipped;
    result["failed"] = summary.failed;
    result["failures"] = summary.failures;
    result["notes"] = notes;
    result["seconds"] = summary.seconds;
    return result;
}

}  // namespace

void bind_experiments(py::module_& m) {
    m.def("run", &run, py::arg("config"), py::arg("threads"), py::arg("out"), py::arg("resume"), py::arg("plots"));
}

}  // namespace mhb::python

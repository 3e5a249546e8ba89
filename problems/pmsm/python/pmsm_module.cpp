// mhbench.pmsm: `fit`, `diagnose` and `simulate` from Python, as the commands of the same names do
// them (problems/pmsm/commands/), with the data a file or a dict of numpy columns and the results as
// Python objects and numpy arrays.
#include <optional>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "framework/python/python_bindings.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/data/settled_measurement.hpp"
#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/model/model_spec.hpp"
#include "problems/pmsm/report/diagnosis_report.hpp"
#include "problems/pmsm/report/fit_report.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"

namespace mhb::pmsm {
namespace {

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace pybind11::literals;
using python::integer_of;
using python::numpy_vector;

std::string path_text(py::handle path) { return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>(); }

bool is_path(py::handle value) { return py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__"); }

// One column of a dict of measurements: 1-D, real, finite, `rows` long (the first column sets it).
Eigen::VectorXd column_of(py::handle values, const std::string& name, Eigen::Index& rows) {
    // As (n, 1): n points of one coordinate, so that a float64 column is read in place.
    const python::Population column(py::module_::import("numpy").attr("asarray")(values).attr("reshape")(-1, 1),
                                    "data['" + name + "']", 1, false);
    const auto n = column.count();
    if (rows >= 0 && n != rows)
        throw py::value_error(fmt::format("data['{}']: {} rows where the columns before have {}", name, n, rows));
    rows = n;
    return column.points().row(0).transpose();
}

Measurement measurement_from_columns(const py::dict& data) {
    Measurement m;
    m.source = "<dict>";
    Eigen::Index rows = -1;
    std::vector<std::string> known;
    for (const char* name : required_columns) known.emplace_back(name);
    for (const char* name : optional_columns) known.emplace_back(name);
    for (const auto& [key, value] : data) {
        const auto name = py::str(key).cast<std::string>();
        if (std::find(known.begin(), known.end(), name) == known.end())
            throw py::value_error(fmt::format("data: unknown column '{}'; the columns are {} (docs/data-format.md)", name,
                                              fmt::join(known, ", ")));
    }
    for (const char* name : required_columns)
        if (!data.contains(name))
            throw py::value_error(fmt::format("data: the column '{}' is missing; {} are required", name,
                                              fmt::join(required_columns, ", ")));
    m.i_d = column_of(data["i_d"], "i_d", rows);
    m.i_q = column_of(data["i_q"], "i_q", rows);
    m.u_d = column_of(data["u_d"], "u_d", rows);
    m.u_q = column_of(data["u_q"], "u_q", rows);
    m.omega_e = column_of(data["omega_e"], "omega_e", rows);
    if (data.contains("t")) m.t = column_of(data["t"], "t", rows);
    if (data.contains("theta_e")) m.theta_e = column_of(data["theta_e"], "theta_e", rows);
    if (data.contains("temp_winding")) m.temp_winding = column_of(data["temp_winding"], "temp_winding", rows);
    if (data.contains("temp_magnet")) m.temp_magnet = column_of(data["temp_magnet"], "temp_magnet", rows);
    if (data.contains("theta_m")) m.theta_m = column_of(data["theta_m"], "theta_m", rows);
    if (data.contains("segment")) {
        // Labels in order of first appearance, as the readers number them.
        const py::list labels = py::module_::import("numpy").attr("asarray")(data["segment"]).attr("astype")("str").attr("tolist")();
        if (static_cast<Eigen::Index>(labels.size()) != rows)
            throw py::value_error(fmt::format("data['segment']: {} rows where the columns before have {}", labels.size(), rows));
        m.segment.resize(rows);
        std::map<std::string, int> index;
        for (Eigen::Index k = 0; k < rows; ++k) {
            const auto label = labels[static_cast<std::size_t>(k)].cast<std::string>();
            if (label.empty()) throw py::value_error(fmt::format("data['segment']: row {} has an empty label", k));
            const auto [it, added] = index.emplace(label, static_cast<int>(m.segment_labels.size()));
            if (added) m.segment_labels.push_back(label);
            m.segment[k] = it->second;
        }
    }
    return m;
}

// The measurement as `fit` and `diagnose` read it: a file (CSV, MAT, HDF5; `columns` and
// `pole_pairs` map its names and units) or a dict of columns named as docs/data-format.md names them.
Measurement measurement_of(py::handle data, double settle, py::handle columns, int pole_pairs) {
    if (is_path(data)) {
        std::string map_text;
        if (!columns.is_none()) {
            if (!py::isinstance<py::dict>(columns))
                throw py::type_error("columns: expects a dict {mhbench column: 'name[unit]' in the file}");
            std::vector<std::string> entries;
            for (const auto& [key, value] : py::reinterpret_borrow<py::dict>(columns))
                entries.push_back(py::str(key).cast<std::string>() + "=" + py::str(value).cast<std::string>());
            map_text = fmt::format("{}", fmt::join(entries, ","));
        }
        const auto map = column_map_from_options(map_text, "", pole_pairs, "Python", "columns");
        return read_settled_measurement(path_text(data), settle, map);
    }
    if (!py::isinstance<py::dict>(data))
        throw py::type_error("data: expects a measurement file's path or a dict of numpy columns (i_d, i_q, u_d, u_q, omega_e, ...)");
    if (!columns.is_none() || pole_pairs != 0) throw py::value_error("columns, pole_pairs: for a file; a dict names mhbench's columns");
    Measurement m = measurement_from_columns(py::reinterpret_borrow<py::dict>(data));
    if (settle > 0) m = select_rows(std::move(m), settled_rows(m, settle));
    if (m.size() < 10) throw py::value_error(fmt::format("data: {} rows{}; a fit needs at least 10", m.size(), settle > 0 ? " after settling" : ""));
    return m;
}

FitOptions fit_options_of(const std::string& optimizer, py::handle evaluations, py::handle seed, py::handle search_rows) {
    OptimizerRegistry::instance().at(optimizer, "optimizer");
    FitOptions options;
    options.optimizer = optimizer;
    options.evaluations = integer_of(evaluations, "evaluations", 0).value_or(0);
    options.seed = python::seed_of(seed, "seed");
    options.search_rows = integer_of(search_rows, "search_rows", 0).value_or(options.search_rows);
    return options;
}

std::optional<tbb::global_control> thread_limit(py::handle threads) {
    const auto n = integer_of(threads, "threads", 1);
    if (!n) return std::nullopt;
    return std::make_optional<tbb::global_control>(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(*n));
}

py::object json_object(const nlohmann::ordered_json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

py::dict fit_result(const Measurement& data, const ModelFit& fit) {
    py::dict out;
    out["model"] = fit.spec.text();
    out["names"] = fit.names;
    out["units"] = fit.units;
    out["values"] = numpy_vector(fit.values);
    out["lower"] = numpy_vector(fit.lower);
    out["upper"] = numpy_vector(fit.upper);
    out["standard_error"] = numpy_vector(fit.standard_error);
    Eigen::VectorXd storage;
    const Eigen::VectorXd& residual = residual_of(data, fit, storage);  // d rows, then q rows
    out["residual_d"] = numpy_vector(residual.head(fit.samples));
    out["residual_q"] = numpy_vector(residual.tail(fit.samples));
    out["report"] = json_object(fit_json(fit));
    out["text"] = fit_text(fit, data);
    return out;
}

// The drive's timing as `control_period`, `carrier_frequency` and `dc_voltage` state it (0: not stated).
DriveTiming timing_of(double control_period, double carrier_frequency, double dc_voltage) {
    if (!(control_period >= 0.0 && control_period <= 1.0)) throw py::value_error("control_period: must lie in [0, 1] s");
    const DriveTiming timing{control_period, carrier_frequency, dc_voltage};
    if (const auto problem = timing_problem(timing); !problem.empty()) throw py::value_error(problem);
    return timing;
}

py::dict fit(py::handle data, const std::string& model, const std::string& optimizer, py::handle evaluations, py::handle seed,
             double settle, py::handle search_rows, py::handle columns, int pole_pairs, py::handle threads, double control_period,
             double carrier_frequency, double dc_voltage) {
    const DriveTiming timing = timing_of(control_period, carrier_frequency, dc_voltage);
    const auto spec = parse_model_spec(model);
    const auto options = fit_options_of(optimizer, evaluations, seed, search_rows);
    auto measurement = measurement_of(data, settle, columns, pole_pairs);
    const auto found = segment_at_operating_points(measurement);
    const auto limit = thread_limit(threads);
    ModelFit result;
    FitCorrections corrections;
    {
        py::gil_scoped_release release;
        result = fit_model(measurement, spec, options);
        corrections = fit_corrections(measurement, result, timing);
    }
    py::dict out = fit_result(measurement, result);
    // As `mhbench fit --json` writes it and prints it.
    py::dict written = out["report"];
    const auto stated = corrections_json(result, corrections);  // a named object: a range-for does not extend a temporary's life before C++23
    for (const auto& [key, value] : stated.items()) written[py::str(key)] = json_object(value);
    out["text"] = py::str(fit_text(result, measurement) + corrections_text(result, corrections));
    if (found) written["operating_points"] = json_object(operating_points_json(*found));
    return out;
}

py::dict diagnose(py::handle data, const std::string& model, const std::string& optimizer, py::handle evaluations,
                  py::handle seed, double settle, py::handle search_rows, py::handle columns, int pole_pairs,
                  py::handle threads, py::handle report, bool whole_laws, double control_period, double carrier_frequency,
                  double dc_voltage) {
    const auto spec = parse_model_spec(model);
    DiagnosisOptions options;
    options.timing = timing_of(control_period, carrier_frequency, dc_voltage);
    options.fit = fit_options_of(optimizer, evaluations, seed, search_rows);
    options.pole_pairs = pole_pairs;
    options.reduced_laws = !whole_laws;
    auto measurement = measurement_of(data, settle, columns, pole_pairs);
    // The report shows a raw log as read, with the windows found in it.
    std::optional<Measurement> raw_log;
    if (!report.is_none() && !measurement.has_segments()) raw_log = measurement;
    const auto found = segment_at_operating_points(measurement);
    const auto limit = thread_limit(threads);
    std::optional<Diagnosis> diagnosis;
    {
        py::gil_scoped_release release;
        diagnosis.emplace(pmsm::diagnose(measurement, spec, options));
    }
    py::dict out;
    out["model"] = spec.text();
    out["recommended"] = diagnosis->recommended.text();
    out["report"] = json_object(diagnosis_json(*diagnosis));
    out["text"] = diagnosis_text(*diagnosis);
    if (found) {
        py::dict written = out["report"];
        written["operating_points"] = json_object(operating_points_json(*found));
    }
    if (!report.is_none()) {
        const std::string source = is_path(data) ? path_text(data) : std::string("<dict>");
        std::optional<FoundOperatingPoints> shown;
        if (found && raw_log) shown.emplace(FoundOperatingPoints{*raw_log, *found});
        const auto written = write_diagnosis_report(path_text(report), measurement, *diagnosis, source, "", shown ? &*shown : nullptr);
        out["report_html"] = written.html.string();
        out["report_markdown"] = written.markdown.string();
        out["report_notes"] = written.notes;
    }
    return out;
}

py::dict measurement_columns(const Measurement& m) {
    py::dict out;
    out["i_d"] = numpy_vector(m.i_d);
    out["i_q"] = numpy_vector(m.i_q);
    out["u_d"] = numpy_vector(m.u_d);
    out["u_q"] = numpy_vector(m.u_q);
    out["omega_e"] = numpy_vector(m.omega_e);
    if (m.t) out["t"] = numpy_vector(*m.t);
    if (m.theta_e) out["theta_e"] = numpy_vector(*m.theta_e);
    if (m.temp_winding) out["temp_winding"] = numpy_vector(*m.temp_winding);
    if (m.temp_magnet) out["temp_magnet"] = numpy_vector(*m.temp_magnet);
    if (m.theta_m) out["theta_m"] = numpy_vector(*m.theta_m);
    if (m.has_segments()) {
        py::list labels;
        for (Eigen::Index k = 0; k < m.segment.size(); ++k) labels.append(m.segment_labels[static_cast<std::size_t>(m.segment[k])]);
        out["segment"] = py::module_::import("numpy").attr("array")(labels, "dtype"_a = "str");
    }
    return out;
}

py::dict simulate(py::handle profile, py::handle base_directory, py::handle seed, py::handle out_file) {
    DriveSimulation spec;
    std::string source;
    if (py::isinstance<py::dict>(profile)) {
        source = "<dict>";
        spec = parse_simulation_profile(python::toml_text_of(profile, "profile"), source,
                                        base_directory.is_none() ? fs::current_path() : fs::path(path_text(base_directory)));
    } else if (is_path(profile)) {
        source = path_text(profile);
        spec = read_simulation_profile(source);
    } else {
        throw py::type_error("profile: expects a simulation profile's path or a dict of the same content");
    }
    if (!seed.is_none()) spec.seed = python::seed_of(seed, "seed");
    SimulationResult result;
    {
        py::gil_scoped_release release;
        try {
            result = pmsm::simulate(spec);
        } catch (const std::invalid_argument& e) {
            throw InputError(source, 0, "", e.what());
        }
    }
    if (!out_file.is_none()) write_simulation(path_text(out_file), spec, result, source);
    py::dict out;
    out["data"] = measurement_columns(result.data);
    out["truth"] = json_object(simulation_sidecar(spec, result, source));
    out["seed"] = spec.seed;
    return out;
}

void bind_pmsm(py::module_& m) {
    m.doc() = "PMSM model identification: fit, diagnose, simulate (use mhbench.pmsm)";
    m.def("fit", &fit, py::arg("data"), py::arg("model"), py::arg("optimizer"), py::arg("evaluations"), py::arg("seed"),
          py::arg("settle"), py::arg("search_rows"), py::arg("columns"), py::arg("pole_pairs"), py::arg("threads"), py::arg("control_period"),
          py::arg("carrier_frequency"), py::arg("dc_voltage"));
    m.def("diagnose", &diagnose, py::arg("data"), py::arg("model"), py::arg("optimizer"), py::arg("evaluations"),
          py::arg("seed"), py::arg("settle"), py::arg("search_rows"), py::arg("columns"), py::arg("pole_pairs"),
          py::arg("threads"), py::arg("report"), py::arg("whole_laws"), py::arg("control_period"),
          py::arg("carrier_frequency"), py::arg("dc_voltage"));
    m.def("simulate", &simulate, py::arg("profile"), py::arg("base_directory"), py::arg("seed"), py::arg("out"));
}

const bool bound = python::register_submodule("_pmsm", bind_pmsm);

}  // namespace
}  // namespace mhb::pmsm

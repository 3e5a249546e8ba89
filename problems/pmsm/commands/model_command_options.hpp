#pragma once
// Options shared by the commands that fit a PMSM model to measurements (`fit`, `diagnose`).
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "framework/cli/option_ranges.hpp"
#include "framework/input_error.hpp"
#include "framework/shell_word.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/operating_points.hpp"
#include "problems/pmsm/data/settled_measurement.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"

namespace mhb::cli {

// Each fit evaluates the model over every sample, so this bounds a fit to hours, not weeks.
inline constexpr std::int64_t max_fit_evaluations = 10'000'000;

struct ModelCommandOptions {
    std::string data, model = "base", json, optimizer = "cmaes";
    std::string model_kind = "steady";
    std::string columns, columns_file;
    int pole_pairs = 0;
    double settle = 0.0;
    pmsm::DriveTiming timing;
    std::int64_t evaluations = 0;
    std::uint64_t seed = 1;
    std::int64_t search_rows = pmsm::FitOptions{}.search_rows;
    int threads = 0;
    pmsm::OperatingPointOptions steady;
};

inline void add_model_options(CLI::App* cmd, ModelCommandOptions& o, const std::string& model_help,
                              const std::string& json_help) {
    cmd->add_option("--data", o.data, "measurement file: CSV, MAT (v5, v7, v7.3) or HDF5 (docs/data-format.md)")->required();
    cmd->add_option("--columns", o.columns,
                    "the file's names and units for mhbench's columns, e.g. i_d=Id_meas[mA],omega_e=speed[rpm]");
    cmd->add_option("--columns-file", o.columns_file, "the same map as a TOML file (docs/data-format.md)");
    cmd->add_option("--pole-pairs", o.pole_pairs, "pole-pair count: converts a speed in rpm to electrical rad/s; diagnose tells harmonics at mechanical orders from electrical ones with it")
        ->check(whole_number_in<int>(1, 1000));
    cmd->add_option("--model", o.model, model_help);
    cmd->add_option("--optimizer", o.optimizer, "optimizer searching the nonlinear effect parameters");
    cmd->add_option("--evaluations", o.evaluations, "optimizer evaluations per fit (0: 150 + 50 per searched parameter)")
        ->check(whole_number_in<std::int64_t>(0, max_fit_evaluations));
    cmd->add_option("--seed", o.seed, "optimizer seed")
        ->check(whole_number_in<std::uint64_t>(0, std::numeric_limits<std::uint64_t>::max()));
    cmd->add_option("--settle", o.settle, "drop this many seconds after each segment start (needs t, segment)")
        ->check(number_in(0.0, 1e6));
    cmd->add_option("--search-rows", o.search_rows,
                    "rows the optimiser searches on, a random subset of longer data (0: all); all rows are polished")
        ->check(whole_number_in<std::int64_t>(0, pmsm::max_measurement_rows));
    cmd->add_option("--threads", o.threads, "worker threads (default: all cores); results do not depend on it")
        ->check(whole_number_in<int>(1, 4096));
    cmd->add_option("--steady-bandwidth", o.steady.bandwidth,
                    "log without a segment column: rows a side of the moving-sum test that finds its steady windows")
        ->check(whole_number_in<Eigen::Index>(2, 1'000'000));
    cmd->add_option("--steady-min-rows", o.steady.min_rows,
                    "log without a segment column: shortest steady window kept (0: three bandwidths)")
        ->check(whole_number_in<Eigen::Index>(0, pmsm::max_measurement_rows));
    cmd->add_option("--steady-false-alarm", o.steady.false_alarm,
                    "log without a segment column: probability of a false change in a log without any")
        ->check(number_in(1e-12, 0.5));
    cmd->add_option("--model-kind", o.model_kind,
                    "steady (di/dt = 0, the default), dynamic (one-step-ahead current prediction on a raw log sampled without gaps) "
                    "or auto (dynamic when the log holds transients its sampling resolves; says which and why)")
        ->check(CLI::IsMember({"steady", "dynamic", "auto"}));
    cmd->add_option("--control-period", o.timing.control_period,
                    "the drive's control period in seconds (currents sampled, voltage updated and held once a period): the base "
                    "parameters are also given corrected for its sample and hold (docs/diagnosis.md); steady-state model only")
        ->check(number_in(0.0, 1.0));
    cmd->add_option("--carrier-frequency", o.timing.carrier_frequency,
                    "with --control-period and --dc-voltage: the PWM carrier (Hz, centred, currents sampled at its peak), whose current "
                    "ripple the correction then includes")
        ->check(number_in(0.0, 1e7));
    cmd->add_option("--dc-voltage", o.timing.dc_voltage, "with --carrier-frequency: the inverter's DC link voltage (V)")->check(number_in(0.0, 1e6));
    cmd->add_option("--current-bandwidth", o.timing.current_bandwidth,
                    "with --control-period: the current loop's closed-loop bandwidth (Hz); the voltages of dead time and flux harmonics "
                    "then reach the logged voltage through the loop, as they do on a drive (docs/diagnosis.md, section 8)")
        ->check(number_in(0.0, 1e6));
    cmd->add_option("--json", o.json, json_help);
}

// " --control-period T [--carrier-frequency F --dc-voltage V]" as given, for the commands suggested next.
inline std::string timing_options_text(const ModelCommandOptions& o) {
    if (!(o.timing.control_period > 0.0)) return {};
    std::string out = fmt::format(" --control-period {:g}", o.timing.control_period);
    if (o.timing.carrier()) out += fmt::format(" --carrier-frequency {:g} --dc-voltage {:g}", o.timing.carrier_frequency, o.timing.dc_voltage);
    if (o.timing.current_bandwidth > 0.0) out += fmt::format(" --current-bandwidth {:g}", o.timing.current_bandwidth);
    return out;
}

// --control-period with --carrier-frequency and --dc-voltage, checked before any data is read;
// `dynamic`: the dynamic model, which the correction is not for.
inline void check_timing_options(const ModelCommandOptions& o, bool dynamic) {
    const auto& t = o.timing;
    if (t.control_period > 0.0 && dynamic)
        throw InputError("command line", 0, "--control-period",
                         "the sample-and-hold correction is for the steady-state model; leave --control-period out with --model-kind dynamic");
    if (const auto problem = pmsm::timing_problem(t); !problem.empty())
        throw InputError("command line", 0,
                         problem.rfind("dc voltage", 0) == 0          ? "--dc-voltage"
                         : problem.rfind("current bandwidth", 0) == 0 ? "--current-bandwidth"
                                                                       : "--carrier-frequency",
                         problem);
}

// The fit settings of the options.
inline pmsm::FitOptions fit_options(const ModelCommandOptions& o) {
    pmsm::FitOptions options;
    options.optimizer = o.optimizer;
    options.evaluations = o.evaluations;
    options.seed = o.seed;
    options.search_rows = o.search_rows;
    return options;
}

// Caps TBB's workers at --threads while it lives (no cap without the option).
inline std::optional<tbb::global_control> thread_limit(const ModelCommandOptions& o) {
    if (o.threads <= 0) return std::nullopt;
    return std::make_optional<tbb::global_control>(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(o.threads));
}

// The column map of --columns, --columns-file and --pole-pairs, checked before any data is read.
inline pmsm::ColumnMap column_map_option(const ModelCommandOptions& o) {
    return pmsm::column_map_from_options(o.columns, o.columns_file, o.pole_pairs);
}

// The measurement of --data under the column map, less --settle after each segment start. What the
// reader passed over (columns or variables not used, blank lines, groups) is printed on stderr, so
// that a column dropped by a typo or a damaged name is seen; a file with thousands of other
// variables gets the first 20 and a count, not a screenful per variable.
inline pmsm::Measurement read_data_option(const ModelCommandOptions& o, const pmsm::ColumnMap& map) {
    constexpr std::size_t shown = 20;
    auto data = pmsm::read_settled_measurement(o.data, o.settle, map);
    for (std::size_t k = 0; k < data.warnings.size() && k < shown; ++k) std::fprintf(stderr, "warning: %s\n", data.warnings[k].c_str());
    if (data.warnings.size() > shown)
        std::fprintf(stderr, "warning: %s: %zu more warnings like these not shown\n", o.data.c_str(), data.warnings.size() - shown);
    return data;
}

// A log without a segment column: its steady windows, found by the moving-sum test, become its
// segments and the transients between them are dropped, so that everything that needs operating
// points has them. A given segment column always wins. Says what was found on stdout.
inline std::optional<pmsm::OperatingPoints> find_operating_points_option(const ModelCommandOptions& o, pmsm::Measurement& data) {
    auto points = pmsm::segment_at_operating_points(data, o.steady);
    if (points) std::printf("%s\n\n", pmsm::operating_points_summary(*points).c_str());
    return points;
}

// The options after --data's value that read the data as this command did, for the commands it
// suggests next: " --columns ... --columns-file ... --pole-pairs N", or "" without a column map.
inline std::string data_reading_options(const ModelCommandOptions& o) {
    std::string out;
    if (!o.columns.empty()) out += " --columns " + shell_word(o.columns);
    if (!o.columns_file.empty()) out += " --columns-file " + shell_word(o.columns_file);
    if (o.pole_pairs > 0) out += " --pole-pairs " + std::to_string(o.pole_pairs);
    return out;
}

// The --optimizer value as a registered optimizer's name; a typo is refused naming the option and
// the closest name, before any data is read.
inline void check_optimizer_option(const std::string& name) {
    try {
        OptimizerRegistry::instance().at(name, "optimizer");
    } catch (const UnknownPlugin& e) {
        throw InputError("command line", 0, "--optimizer", e.what());
    }
}

}  // namespace mhb::cli

// `mhbench fit --data D.csv --model MODEL [--optimizer NAME] [--json OUT]`: identifies every parameter
// of a model (base + effects, docs/effects.md) with 95 % intervals, and prints the residual rms of
// u_d, u_q and combined, overall and per segment.
#include <memory>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "problems/pmsm/commands/model_command_options.hpp"
#include "framework/file_output.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/fit/dynamic_fit.hpp"
#include "problems/pmsm/report/diagnosis_report.hpp"
#include "problems/pmsm/report/fit_report.hpp"

namespace mhb::cli {
namespace {

const bool registered = register_command("fit", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("fit", "Fit a PMSM model (base + effects) to measurements: parameters, 95 % intervals, residuals");
    auto o = std::make_shared<ModelCommandOptions>();
    add_model_options(cmd, *o, "model, e.g. base+deadtime+delay(tau=150e-6) (docs/effects.md)", "write the fit as JSON here");
    return std::function<int()>([o] {
        const auto spec = pmsm::parse_model_spec(o->model);
        check_optimizer_option(o->optimizer);
        check_timing_options(*o, false);
        const auto columns = column_map_option(*o);
        const auto threads = thread_limit(*o);
        auto data = read_data_option(*o, columns);
        pmsm::state_current_loop(data, o->timing);
        auto kind = pmsm::parse_model_kind(o->model_kind);
        if (kind == pmsm::ModelKind::Auto) {
            const auto choice = pmsm::choose_model_kind(data, spec);
            fmt::print("model kind: {}\n\n", choice.reason);
            kind = choice.kind;
        }
        if (kind == pmsm::ModelKind::Dynamic) {
            check_timing_options(*o, true);
            // Every row: the transients are what the dynamic model learns from, and rows dropped by
            // --settle would leave gaps whose row numbers are not the file's.
            if (o->settle > 0.0)
                throw InputError("command line", 0, "--settle",
                                 "the dynamic model uses every row, the settling included; leave --settle out with --model-kind dynamic");
            const auto fit = pmsm::fit_dynamic_model(data, spec);
            fmt::print("{}", pmsm::dynamic_fit_text(fit, data));
            if (!o->json.empty()) {
                auto out = pmsm::dynamic_fit_json(fit);
                out["data"] = o->data;
                replace_file(o->json, out.dump(2) + "\n");
                fmt::print("\nJSON: {}\n", o->json);
            }
            return exit_ok;
        }
        const auto found = find_operating_points_option(*o, data);
        const auto fit = pmsm::fit_model(data, spec, fit_options(*o));
        fmt::print("{}", pmsm::fit_text(fit, data));
        const auto corrections = pmsm::fit_corrections(data, fit, o->timing);
        fmt::print("{}", pmsm::corrections_text(fit, corrections));
        if (!o->json.empty()) {
            auto out = pmsm::fit_json(fit);
            out["data"] = o->data;
            out.update(pmsm::corrections_json(fit, corrections));
            if (found) out["operating_points"] = pmsm::operating_points_json(*found);
            replace_file(o->json, out.dump(2) + "\n");
            fmt::print("\nJSON: {}\n", o->json);
        }
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli

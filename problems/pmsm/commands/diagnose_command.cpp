// `mhbench diagnose --data D.csv --model MODEL [--json OUT] [--report DIR]`: fits MODEL, then says
// where it fails, which library effect is most likely missing and how sure that is
// (docs/effects.md, "How diagnose decides"; docs/tutorial-missing-physics.md).
#include <memory>
#include <optional>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "problems/pmsm/commands/model_command_options.hpp"
#include "framework/file_output.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/fit/dynamic_fit.hpp"
#include "problems/pmsm/report/diagnosis_report.hpp"

namespace mhb::cli {
namespace {

struct DiagnoseCommandOptions : ModelCommandOptions {
    std::string report;
    bool whole_laws = false;
};

const bool registered = register_command("diagnose", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("diagnose", "Diagnose a PMSM model against measurements: where it fails, which effect is missing, how sure");
    auto o = std::make_shared<DiagnoseCommandOptions>();
    add_model_options(cmd, *o, "model to diagnose, e.g. base or base+deadtime (docs/effects.md)",
                      "write the diagnosis as JSON here");
    cmd->add_option("--report", o->report, "write report.md with PNG plots, and report.html (one page, plots inline), into this directory");
    cmd->add_flag("--whole-laws", o->whole_laws,
                  "add an effect of several terms (saturation) only as its whole law, never with fewer terms when the log's operating "
                  "points cannot pin them all (docs/diagnosis.md, section 1)");
    return std::function<int()>([o] {
        const auto spec = pmsm::parse_model_spec(o->model);
        check_optimizer_option(o->optimizer);
        check_timing_options(*o, false);
        const auto columns = column_map_option(*o);
        const auto threads = thread_limit(*o);
        auto data = read_data_option(*o, columns);
        pmsm::state_current_loop(data, o->timing);
        // The diagnosis compares many fits of the steady model; the dynamic model is fitted by `fit` only
        // so far, so `auto` states its choice and falls back.
        const auto kind = pmsm::parse_model_kind(o->model_kind);
        if (kind == pmsm::ModelKind::Dynamic)
            throw InputError("command line", 0, "--model-kind",
                             "diagnose has only the steady model so far; the dynamic model is fitted by `mhbench fit --model-kind dynamic`");
        if (kind == pmsm::ModelKind::Auto) {
            const auto choice = pmsm::choose_model_kind(data, spec);
            fmt::print("model kind: steady ({}{})\n\n", choice.kind == pmsm::ModelKind::Dynamic ? "auto would choose " : "auto: ",
                       choice.kind == pmsm::ModelKind::Dynamic
                           ? choice.reason + "; but diagnose has only the steady model so far, so it falls back to it"
                           : choice.reason.substr(std::string("steady: ").size()));
        }
        // The report shows the log as read, with the windows found in it shaded.
        std::optional<pmsm::Measurement> raw_log;
        if (!o->report.empty() && !data.has_segments()) raw_log = data;
        const auto found = find_operating_points_option(*o, data);
        pmsm::DiagnosisOptions options;
        options.fit = fit_options(*o);
        options.pole_pairs = columns.pole_pairs.value_or(0);
        options.reduced_laws = !o->whole_laws;
        options.timing = o->timing;
        const auto diagnosis = pmsm::diagnose(data, spec, options);
        fmt::print("{}", pmsm::diagnosis_text(diagnosis));
        if (diagnosis.recommended.text() != spec.text())
            fmt::print("\nnext: mhbench fit --data {}{} --model {}{}\n", shell_word(o->data), data_reading_options(*o),
                       shell_word(diagnosis.recommended.text()),
                       timing_options_text(*o));
        if (!o->json.empty()) {
            auto out = pmsm::diagnosis_json(diagnosis);
            out["data"] = o->data;
            if (found) out["operating_points"] = pmsm::operating_points_json(*found);
            replace_file(o->json, out.dump(2) + "\n");
            fmt::print("\nJSON: {}\n", o->json);
        }
        if (!o->report.empty()) {
            std::optional<pmsm::FoundOperatingPoints> shown;
            if (found && raw_log) shown.emplace(pmsm::FoundOperatingPoints{*raw_log, *found});
            const auto outcome =
                pmsm::write_diagnosis_report(o->report, data, diagnosis, o->data, data_reading_options(*o), shown ? &*shown : nullptr);
            fmt::print("{}report: {} and {} ({} plots)\n", o->json.empty() ? "\n" : "", outcome.markdown.string(),
                       outcome.html.string(), outcome.images.size());
            for (const auto& note : outcome.notes) fmt::print("note: {}\n", note);
        }
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli

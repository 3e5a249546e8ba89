// `mhbench fit --data D.csv --model MODEL [--optimizer NAME] [--json OUT]`: identifies every parameter
// of a model (base + effects, docs/effects.md) with 95 % intervals, and prints the residual rms of
// u_d, u_q and combined, overall and per segment.
#include <fstream>
#include <memory>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/diagnosis_report.hpp"

namespace mhb::cli {
namespace {

struct FitCommandOptions {
    std::string data, model = "base", json, optimizer = "cmaes";
    double settle = 0.0;
    std::int64_t evaluations = 0;
    std::uint64_t seed = 1;
};

const bool registered = register_command("fit", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("fit", "Fit a PMSM model (base + effects) to measurements: parameters, 95 % intervals, residuals");
    auto o = std::make_shared<FitCommandOptions>();
    cmd->add_option("--data", o->data, "measurement CSV (docs/data-format.md)")->required();
    cmd->add_option("--model", o->model, "model, e.g. base+deadtime+delay(tau=150e-6) (docs/effects.md)");
    cmd->add_option("--optimizer", o->optimizer, "optimizer searching the nonlinear effect parameters");
    cmd->add_option("--evaluations", o->evaluations, "optimizer evaluations (0: 150 + 50 per searched parameter)");
    cmd->add_option("--seed", o->seed, "optimizer seed");
    cmd->add_option("--settle", o->settle, "drop this many seconds after each segment start (needs t, segment)");
    cmd->add_option("--json", o->json, "write the fit as JSON here");
    return std::function<int()>([o] {
        const auto spec = pmsm::parse_model_spec(o->model);
        OptimizerRegistry::instance().at(o->optimizer, "optimizer");
        const auto data = pmsm::read_settled_measurement(o->data, o->settle);
        pmsm::FitOptions options;
        options.optimizer = o->optimizer;
        options.evaluations = o->evaluations;
        options.seed = o->seed;
        const auto fit = pmsm::fit_model(data, spec, options);
        fmt::print("{}", pmsm::fit_text(fit, data));
        if (!o->json.empty()) {
            auto out = pmsm::fit_json(fit);
            out["data"] = o->data;
            std::ofstream(o->json) << out.dump(2) << "\n";
            fmt::print("\nJSON: {}\n", o->json);
        }
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli

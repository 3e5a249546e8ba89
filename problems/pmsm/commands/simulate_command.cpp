// `mhbench simulate PROFILE.toml --out data.csv [--seed N]`: runs the PMSM drive simulator on a
// profile and writes the measurement CSV with its JSON sidecar (data.json) beside it.
#include <cstdio>
#include <limits>
#include <memory>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/cli/option_ranges.hpp"
#include "framework/input_error.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"

namespace mhb::cli {
namespace {

struct SimulateOptions {
    std::string profile;
    std::string out;
    std::uint64_t seed = 0;
    CLI::Option* seed_option = nullptr;
};

const bool registered = register_command("simulate", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("simulate", "Simulate a PMSM drive profile; write measurement CSV and JSON sidecar");
    auto options = std::make_shared<SimulateOptions>();
    cmd->add_option("profile", options->profile, "simulation profile (TOML, see docs/pmsm.md)")->required();
    cmd->add_option("--out", options->out, "measurement CSV to write (the sidecar goes beside it as .json)")->required();
    options->seed_option = cmd->add_option("--seed", options->seed, "noise seed, overriding noise.seed of the profile")
                               ->check(whole_number_in<std::uint64_t>(0, std::numeric_limits<std::int64_t>::max()));
    return std::function<int()>([options] {
        auto spec = pmsm::read_simulation_profile(options->profile);
        if (options->seed_option->count() > 0) spec.seed = options->seed;
        pmsm::SimulationResult result;
        try {
            result = pmsm::simulate(spec);
        } catch (const std::invalid_argument& e) {
            throw InputError(options->profile, 0, "", e.what());
        } catch (const std::runtime_error& e) {
            std::fprintf(stderr, "error: %s: simulation failed: %s\n", options->profile.c_str(), e.what());
            return exit_trial_failures;
        }
        pmsm::write_simulation(options->out, spec, result, options->profile);
        fmt::print("{}: {} samples in {} segments, {:.3f} s simulated ({} RK4 steps), seed {}\n", options->out,
                   result.data.size(), result.segments.size(), result.simulated_time, result.integration_steps, spec.seed);
        fmt::print("sidecar: {}\n", pmsm::sidecar_path(options->out).string());
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli

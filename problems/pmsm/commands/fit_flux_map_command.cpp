// `mhbench fit-flux-map --map FILE [--plot OUT.png]`: fits the power-law magnetic model to a measured
// flux map, prints its parameters and misfit, and draws map against model.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/input_error.hpp"
#include "framework/plots.hpp"
#include "problems/pmsm/machine/power_law_flux_fit.hpp"

namespace mhb::cli {
namespace {

struct FitFluxMapOptions {
    std::string map, plot;
};

// The grid values nearest to the given fractions of the grid's span: the slices the plot shows.
std::vector<double> slices(const std::vector<double>& grid, std::initializer_list<double> fractions) {
    std::vector<double> out;
    for (double f : fractions) {
        const double value = grid.front() + f * (grid.back() - grid.front());
        double nearest = grid.front();
        for (double g : grid)
            if (std::abs(g - value) < std::abs(nearest - value)) nearest = g;
        out.push_back(nearest);
    }
    return out;
}

// psi_d against i_d at a few i_q (left), psi_q against i_q at a few i_d (right): the map's points
// and the model's curves in one data file, one gnuplot index per slice and kind.
void write_comparison_plot(const std::filesystem::path& png, const pmsm::FluxMap& map, const pmsm::PowerLawFlux& model) {
    const std::filesystem::path base = png.parent_path() / png.stem();
    const std::filesystem::path data = png.parent_path() / "plot-data" / (png.stem().string() + ".dat");
    std::filesystem::create_directories(data.parent_path());
    std::ofstream out(data);
    const auto& grid_d = map.i_d_grid();
    const auto& grid_q = map.i_q_grid();
    std::string left, right;
    int index = 0;
    auto panel = [&](bool d_axis, std::string& plot) {
        const auto& along = d_axis ? grid_d : grid_q;
        // psi_d is even in i_q, so its slices need only i_q >= 0; psi_q's differ on both sides of i_d = 0.
        const auto across = d_axis ? slices(grid_q, {0.5, 0.67, 0.83, 1.0}) : slices(grid_d, {0.0, 0.5, 0.75, 1.0});
        for (std::size_t s = 0; s < across.size(); ++s) {
            auto current = [&](double x) { return d_axis ? pmsm::Complex{x, across[s]} : pmsm::Complex{across[s], x}; };
            auto component = [&](pmsm::Complex psi) { return d_axis ? psi.real() : psi.imag(); };
            for (double x : along) out << fmt::format("{} {}\n", x, component(map.flux(current(x), map.nominal_psi_f())));
            out << "\n\n";
            for (int k = 0; k <= 200; ++k) {
                const double x = along.front() + (along.back() - along.front()) * k / 200.0;
                out << fmt::format("{} {}\n", x, component(model.flux_of_current(current(x))));
            }
            out << "\n\n";
            const std::string label = fmt::format("{} = {:g} A", d_axis ? "i_q" : "i_d", across[s]);
            plot += fmt::format("{}{} index {} with points pt 7 ps 0.6 lc {} title {}, {} index {} with lines lw 2 lc {} notitle",
                                plot.empty() ? "plot " : ", ", gnuplot_quote(data.string()), index, s + 1,
                                gnuplot_quote("map, " + label), gnuplot_quote(data.string()), index + 1, s + 1);
            index += 2;
        }
    };
    panel(true, left);
    panel(false, right);
    out.close();
    const std::string body = fmt::format(
        "set multiplot layout 1,2 title {}\nset grid\nset key left top\n"
        "set xlabel 'i_d (A)'\nset ylabel '{{/Symbol y}}_d (Wb)'\n{}\n"
        "set xlabel 'i_q (A)'\nset ylabel '{{/Symbol y}}_q (Wb)'\n{}\nunset multiplot",
        gnuplot_quote("measured flux map (points) and fitted power-law model (lines)"), left, right);
    std::string error;
    if (!render_gnuplot(base, body, 1200, 520, error)) throw std::runtime_error(error);
}

const bool registered = register_command("fit-flux-map", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("fit-flux-map", "Fit the power-law magnetic model to a measured flux map; print and plot the misfit");
    auto options = std::make_shared<FitFluxMapOptions>();
    cmd->add_option("--map", options->map, "flux map CSV (columns i_d_A, i_q_A, psi_d_Vs, psi_q_Vs)")->required();
    cmd->add_option("--plot", options->plot, "PNG to write, map against model (an SVG goes beside it)");
    return std::function<int()>([options] {
        // The nominal magnet flux only matters to a plant that changes it; the map is read as it is.
        const auto map = pmsm::FluxMap::read(options->map, 1.0);
        const auto fit = pmsm::fit_flux_model(map);
        const auto& p = fit.parameters;
        fmt::print("{}: {} points, base current {:g} A, base flux {:g} Wb (the map's largest |i| and |psi|)\n", options->map,
                   map.i_d_grid().size() * map.i_q_grid().size(), p.base_current, p.base_flux);
        const auto values = p.values();
        for (int k = 0; k < pmsm::PowerLawSaturation::count; ++k)
            fmt::print("  {:<6} {:.6g}\n", pmsm::PowerLawSaturation::parameter_names()[k], values[k]);
        const pmsm::PowerLawFlux model(p);
        fmt::print("magnet flux psi_d(0, 0): model {:.4f} Wb, map {:.4f} Wb\n", model.magnet_flux(), map.magnet_flux());
        fmt::print("psi_d: rms {:.4f} Wb = {:.2f} % of the map's span {:.4f} Wb, largest {:.4f} Wb\n", fit.rms_d,
                   100.0 * fit.relative_rms_d(), fit.span_d, fit.max_error_d);
        fmt::print("psi_q: rms {:.4f} Wb = {:.2f} % of the map's span {:.4f} Wb, largest {:.4f} Wb\n", fit.rms_q,
                   100.0 * fit.relative_rms_q(), fit.span_q, fit.max_error_q);
        fmt::print("{} Levenberg-Marquardt iterations\n", fit.iterations);
        if (!options->plot.empty()) {
            try {
                write_comparison_plot(options->plot, map, model);
            } catch (const std::runtime_error& e) {
                std::fprintf(stderr, "error: %s\n", e.what());
                return exit_trial_failures;
            }
            fmt::print("plot: {}\n", options->plot);
        }
        return exit_ok;
    });
});

}  // namespace
}  // namespace mhb::cli

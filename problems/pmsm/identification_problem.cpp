// Problem `pmsm_identification`: the seed's electrical-parameter identification (its eq. 6 and
// Table 2) fitted to a measurement file. The fitness is a quadratic in (Rs, Ld, Lq, psi_f), so a
// whole population is evaluated from precomputed least-squares statistics at O(1) per candidate, and
// the exact optimum is known (docs/pmsm.md).
#include <filesystem>
#include <memory>
#include <optional>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/pmsm/fit/base_model_fit.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"

namespace mhb::pmsm {
namespace {

// What every trial's instance reads and precomputes from the measurement: the same for all of them.
struct MeasurementStatistics {
    Measurement data;               // the settled rows
    Eigen::Index total_samples = 0;
    BaseModelFit fit;
    std::optional<Eigen::Vector4d> truth;  // from the simulation sidecar, when there is one
};

MeasurementStatistics read_statistics(const std::filesystem::path& path, const ColumnMap& map, double settle, Fitness fitness,
                                      CovarianceMethod method) {
    MeasurementStatistics s;
    Measurement all = read_measurement(path, map);
    const auto rows = settled_rows(all, settle);
    if (rows.size() < 3)
        throw InputError(path.string(), 0, "settle",
                         fmt::format("dropping {} s after each segment start leaves {} samples; at least 3 are needed", settle, rows.size()));
    s.total_samples = all.size();
    s.data = select_rows(std::move(all), rows);
    s.fit = fit_base_model(s.data, fitness, method);
    s.truth = read_sidecar_truth(path);
    return s;
}

class PmsmIdentification final : public Problem {
public:
    PmsmIdentification(const ParameterSet& p, const ProblemContext& context) {
        const std::string& data = p.text("data");
        if (data.empty()) throw ParameterError("data", "required: the measurement CSV to fit (docs/data-format.md)");
        shown_path_ = data;
        path_ = std::filesystem::path(data).is_absolute() ? std::filesystem::path(data) : context.base_directory / data;
        const double settle = p.real("settle");
        const Fitness fitness = parse_fitness(p.text("fitness"));
        const CovarianceMethod method = p.text("uncertainty") == "white" ? CovarianceMethod::White : CovarianceMethod::NeweyWest;
        // A log's own column names and units, as `fit --columns` takes them.
        const std::string& columns_file = p.text("columns_file");
        const std::filesystem::path map_path =
            columns_file.empty() || std::filesystem::path(columns_file).is_absolute() ? std::filesystem::path(columns_file)
                                                                                       : context.base_directory / columns_file;
        const ColumnMap map = column_map_from_options(p.text("columns"), map_path.string(), static_cast<int>(p.integer("pole_pairs")),
                                                      "problem parameter", "columns");
        auto build = [&] { return read_statistics(path_, map, settle, fitness, method); };
        if (context.shared) {
            const std::string key = fmt::format("pmsm_identification|{}|{}|{}|{}|{}|{}|{}",
                                                std::filesystem::absolute(path_).lexically_normal().string(), settle, p.text("fitness"),
                                                p.text("uncertainty"), p.text("columns"), map_path.string(), p.integer("pole_pairs"));
            statistics_ = context.shared->get<MeasurementStatistics>(key, build);
        } else {
            statistics_ = std::make_shared<const MeasurementStatistics>(build());
        }
        const BaseModelFit& fit = statistics_->fit;

        const Bounds box = base_parameter_bounds();
        set_domain(box.lower, box.upper, base_parameter_names);
        if (statistics_->truth) truth_.true_parameters = Vector(*statistics_->truth);
        set_reference(fit.in_bounds, "Table 2's box");
        gram_ = fit.least_squares.gram;
        centre_ = fit.least_squares.solution;
        scale_ = 1.0 / static_cast<double>(fit.samples);
        rss_ = fit.least_squares.rss;
    }

    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        for (Eigen::Index j = 0; j < x.cols(); ++j) {
            const Eigen::Vector4d d = x.col(j) - centre_;
            f[j] = (rss_ + d.dot(gram_ * d)) * scale_;
        }
    }

    std::string describe() const override {
        const auto& fit = statistics_->fit;
        const auto& data = statistics_->data;
        const auto& u = fit.uncertainty;
        std::string text = fmt::format("data {}: {} of {} samples", shown_path_, data.size(), statistics_->total_samples);
        if (data.has_segments()) text += fmt::format(" in {} segments", data.segment_labels.size());
        text += fmt::format("; fitness {}; residual d {:.3g} V, q {:.3g} V (lag-1 correlation {:.2f}, {:.2f}); "
                            "least-squares optimum, 95 % {}:",
                            to_string(fit.fitness), fit.axis_noise[0], fit.axis_noise[1], u.axis_rho[0], u.axis_rho[1],
                            to_string(u.method));
        for (int j = 0; j < 4; ++j)
            text += fmt::format(" {} = {:.6g} ± {:.2g}", base_parameter_names[static_cast<std::size_t>(j)],
                                fit.least_squares.solution[j], u.critical_value * u.standard_error[j]);
        for (const auto& w : data.warnings) text += "; " + w;
        return text;
    }

protected:
    void bounds_changed() override { set_reference(box_least_squares(statistics_->fit.least_squares, bounds()), "the experiment's box"); }

private:
    // The exact optimum inside the search box is the reference every optimiser should reach.
    void set_reference(const BoxLeastSquares& optimum, const std::string& box_name) {
        truth_.reference_solution = optimum.solution;
        truth_.reference_fitness = optimum.rss / static_cast<double>(statistics_->fit.samples);
        truth_.optimum_value = truth_.reference_fitness;
        truth_.reference_label = "least-squares optimum";
        if (optimum.any_bound_active()) {
            std::string active;
            for (std::size_t j = 0; j < 4; ++j)
                if (optimum.at_bound[j] != 0)
                    active += fmt::format("{}{} at its {} bound", active.empty() ? "" : ", ", base_parameter_names[j],
                                          optimum.at_bound[j] < 0 ? "lower" : "upper");
            truth_.reference_label += " (inside " + box_name + ": " + active + ")";
        }
    }

    std::filesystem::path path_;
    std::string shown_path_;  // as the config wrote it, so tables do not depend on where the checkout lives
    std::shared_ptr<const MeasurementStatistics> statistics_;
    Eigen::Matrix4d gram_;
    Eigen::Vector4d centre_;
    double scale_ = 1.0, rss_ = 0.0;
};

const bool registered = register_problem({
    "pmsm_identification",
    "PMSM electrical parameters (Rs, Ld, Lq, psi_f) from drive data, seed eq. (6), box of Table 2",
    {ParameterSpec::text("data", "", "measurement CSV (docs/data-format.md), relative to the experiment file"),
     ParameterSpec::choice("fitness", "mse", {"mse", "noise_weighted"},
                           "mean squared dq-voltage error, or each axis divided by its LS residual variance"),
     ParameterSpec::real("settle", 0.0, 0.0, 1e6, "drop samples this long after each segment start (needs t, segment)", "s"),
     ParameterSpec::choice("uncertainty", "newey_west", {"newey_west", "white"},
                           "covariance of the reported least-squares optimum (serially correlated or white errors)"),
     ParameterSpec::text("columns", "", "the log's own column names and units, as fit --columns: i_d=Id[mA],omega_e=n[rpm],..."),
     ParameterSpec::text("columns_file", "", "the same map as a TOML file (docs/data-format.md), relative to the experiment file"),
     ParameterSpec::integer("pole_pairs", 0, 0, 1000, "pole-pair count for speeds in rpm (0: not given)")},
    [](const ParameterSet& p, const ProblemContext& c) { return std::make_unique<PmsmIdentification>(p, c); },
});

}  // namespace
}  // namespace mhb::pmsm

#pragma once
// Fitting a model (base + effects, model_spec.hpp) to a measurement. For fixed effect parameters the
// prediction is affine in the base parameters (Rs, Ld, Lq, psi_f) for every library effect: effects add
// terms, rescale R_s or psi_f, or rotate currents and voltages. So the base parameters are solved by
// linear least squares for any effect values (variable projection), and only the effect parameters
// are searched: first by a framework optimiser inside their declared plausible box, then polished by
// Levenberg-Marquardt on the projected residual. Intervals come from the Jacobian of the whole model
// with the serial-correlation-aware covariance of linear_fit.hpp (docs/effects.md, "Fitting").
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/fit/linear_fit.hpp"
#include "problems/pmsm/model/model_spec.hpp"

namespace mhb::pmsm {

// Fewer segments than this give a jackknife too noisy to judge intervals by.
inline constexpr std::size_t minimum_jackknife_segments = 6;

struct FitOptions {
    std::string optimizer = "cmaes";
    std::int64_t evaluations = 0;  // optimiser budget; 0: 150 + 50 per searched parameter
    std::uint64_t seed = 1;
    CovarianceMethod covariance = CovarianceMethod::NeweyWest;
    // The optimiser searches on at most this many rows, drawn at random without replacement (the
    // same rows for the same seed), and Levenberg-Marquardt then polishes on all rows: the global
    // search only has to find the basin, and its cost stops growing with the log's length. Random
    // rather than every k-th row, so that the subsample cannot alias with the electrical angle.
    // 0: always all rows.
    std::int64_t search_rows = 3000;
    // Whether to compute the intervals (a Jacobian of the whole model and its covariance); off for
    // the many fits a search compares by their residual alone.
    bool intervals = true;
    // Whether the fit keeps its residual (ModelFit::residual, two doubles per row); off for fits that
    // are compared by their sums of squares and segment summaries, which are always kept.
    bool keep_residual = true;
};

struct AxisRms {
    double d = 0.0, q = 0.0, total = 0.0;  // V; total = sqrt((d^2 + q^2) / 2)
};

struct SegmentResidual {
    std::string label;
    Eigen::Index first = 0, rows = 0;
    AxisRms rms;
    Eigen::Vector2d mean{0.0, 0.0};  // mean residual of u_d and u_q over the segment (V)
};

struct SegmentSums;

struct ModelFit {
    ModelSpec spec;
    std::vector<std::string> names;      // all parameters: Rs, Ld, Lq, psi_f, then effect.parameter
    std::vector<std::string> units;
    std::vector<bool> free;              // fitted (true) or fixed by the spec
    Eigen::VectorXd values;              // all parameters
    Eigen::VectorXd lower, upper;        // 95 % interval; NaN when the data do not determine it, the value when fixed
    Eigen::VectorXd standard_error;      // NaN as above, 0 when fixed
    Eigen::VectorXd range_lower, range_upper;  // Table 2's box for the base, each effect's plausible range for these data
    std::vector<bool> periodic;          // angles whose range is a full turn
    Eigen::Index samples = 0;
    Eigen::VectorXd residual;            // logged minus predicted: samples d rows, then samples q rows (empty unless kept)
    Eigen::Vector2d axis_rss{0.0, 0.0};  // sum of squared residuals of u_d and u_q
    AxisRms rms;
    std::vector<SegmentResidual> segments;  // one per segment (one "all" when the data have none)
    ParameterUncertainty uncertainty;    // of the free parameters (in the order of `free`)
    // Per parameter: its interval is the jackknife's over segments, wider than the model-based one,
    // because the segments pull it apart by more than the noise would (the model misses structure
    // between them); empty when no intervals were computed or the data have too few segments.
    std::vector<bool> segment_spread;
    bool spread_widened(Eigen::Index j) const {
        return static_cast<std::size_t>(j) < segment_spread.size() && segment_spread[static_cast<std::size_t>(j)];
    }
    // The per-segment normal equations its intervals were judged with, of all free parameters at
    // `values`, kept for its leave-one-segment-out prediction (the same sums); null when no intervals
    // were computed or the data have fewer than three segments.
    std::shared_ptr<const SegmentSums> segment_sums;
    std::int64_t evaluations = 0;        // optimiser evaluations
    int polish_iterations = 0;           // Levenberg-Marquardt iterations
    std::string method;                  // how it was fitted, in words

    double rss() const { return axis_rss.sum(); }
    double rss_axis(int axis) const { return axis_rss[axis]; }
    Eigen::Index free_count() const;
    Eigen::Index index_of(const std::string& name) const;  // -1 when absent
    // Free parameter at a bound of its range (a periodic angle never is).
    bool at_bound(Eigen::Index j) const;
    // Free effect parameter outside its plausible range for these data (inside the declared range the
    // fit searched, SteadyStateModel::plausible).
    bool beyond_range(Eigen::Index j) const;
    // What the model's effects do to the base parameters that no log shows (Effect::unseen_bias), one
    // sentence each and the parameters it moves: biases the intervals do not hold.
    std::vector<UnseenBias> unseen_biases() const;
};

// Fits `spec` to all rows of `data`. Effect parameters listed in `search` (indices into the model's
// parameters) are searched by the optimiser; the other free effect parameters start at `start` (all
// parameters; nullptr: the effects' defaults) and are only polished, as are the searched ones. An
// empty `search` with a nullptr `start` searches every free effect parameter.
// The fit's residual: its own when kept, else recomputed from its spec and values into `storage`.
const Eigen::VectorXd& residual_of(const Measurement& data, const ModelFit& fit, Eigen::VectorXd& storage);

// The rows the optimiser searches on (FitOptions::search_rows): all of them, or a sorted random subset.
std::vector<Eigen::Index> search_subsample(Eigen::Index rows, const FitOptions& options);

ModelFit fit_model(const Measurement& data, const ModelSpec& spec, const FitOptions& options,
                   const Eigen::VectorXd* start = nullptr, const std::vector<Eigen::Index>& search = {});

// Levenberg-Marquardt from `start` only (no global search), e.g. to refit on part of the data; of
// `options`, the covariance, intervals and keep_residual apply.
ModelFit polish_model(const Measurement& data, const ModelSpec& spec, const Eigen::VectorXd& start, const FitOptions& options = {});
// The same, returning only the parameter values (no residual summaries, no intervals).
Eigen::VectorXd refine_parameters(const SteadyStateModel& model, const ModelSpec& spec, const Eigen::VectorXd& start);

// Predicted logged voltages of `model` at `values`, stacked d then q.
Eigen::VectorXd predict_stacked(const SteadyStateModel& model, const Eigen::VectorXd& values);
// Logged minus predicted voltages of `model` at `values`, stacked d then q.
Eigen::VectorXd residual_stacked(const SteadyStateModel& model, const Eigen::VectorXd& values);

// d prediction / d parameter for the listed parameters (stacked d then q rows): exact for the base
// parameters (the prediction is affine in them), central differences (one-sided at a bound) with a
// step of 1e-4 of the declared range for effect parameters.
Eigen::MatrixXd prediction_jacobian(const SteadyStateModel& model, const Eigen::VectorXd& values,
                                    const std::vector<Eigen::Index>& columns);
// The same for the rows of block b (model.block_first(b), model.block_size(b) of them), d rows into
// `d` and q rows into `q`, for a caller that reduces the Jacobian a block at a time. Uses this thread's
// scratch of the model; `at` must hold `values` and is left so.
void block_jacobian(const SteadyStateModel& model, const Eigen::VectorXd& values, const std::vector<Eigen::Index>& columns,
                    Eigen::Index b, Eigen::VectorXd& at, Eigen::Ref<Eigen::MatrixXd> d, Eigen::Ref<Eigen::MatrixXd> q);

// The model linearised at `values` in the listed parameters (the prediction Jacobian J, columns as
// prediction_jacobian) and reduced over each range of rows: J'J, J'r and r'r with r the residual at
// `values`. `starts` are the first rows of consecutive ranges (starts[0] = 0) that cover all rows.
// Computed a block of rows at a time, blocks in parallel, without a row-sized array. With `residual`
// (stacked d then q, as residual_stacked) J'r and r'r are of it instead.
struct RangeNormalEquations {
    std::vector<Eigen::MatrixXd> gram;
    std::vector<Eigen::VectorXd> moment;
    std::vector<double> total;
};
RangeNormalEquations range_normal_equations(const SteadyStateModel& model, const Eigen::VectorXd& values,
                                            const std::vector<Eigen::Index>& columns, const std::vector<Eigen::Index>& starts,
                                            const Eigen::VectorXd* residual = nullptr);
// The same for several partitions of the rows (each a `starts`) in one pass: one Jacobian of each
// block, the sums of each partition the numbers range_normal_equations gives for it alone.
std::vector<RangeNormalEquations> partitioned_normal_equations(const SteadyStateModel& model, const Eigen::VectorXd& values,
                                                         const std::vector<Eigen::Index>& columns,
                                                         const std::vector<std::vector<Eigen::Index>>& partitions,
                                                         const Eigen::VectorXd* residual = nullptr);
// The sums of some of the columns they were made with (`positions` index those columns): the numbers
// range_normal_equations gives for those columns alone, since each entry is reduced on its own.
RangeNormalEquations select_columns(const RangeNormalEquations& sums, const std::vector<Eigen::Index>& positions);

// A fit's per-segment normal equations (ModelFit::segment_sums) and what they are of.
struct SegmentSums {
    const void* data = nullptr;  // the Measurement fitted, only compared: sums of other data are not these
    Eigen::Index samples = 0;
    Eigen::VectorXd values;
    std::vector<Eigen::Index> columns;  // all free parameters
    std::vector<Eigen::Index> starts;   // each segment's first row
    RangeNormalEquations sums;
};
// Each range left out in turn: the Gauss-Newton step (column r for range r) that the other ranges'
// normal equations ask of the parameters; a parameter they do not determine does not move.
Eigen::MatrixXd leave_one_range_out_steps(const RangeNormalEquations& sums);

// Which of the model's parameters (base first) are angles whose range is a full turn.
std::vector<bool> periodic_parameters(const SteadyStateModel& model);
// Whether `value` sits at an end of its range [lo, hi] (within 1e-9 of its width); an angle of a full
// turn never does.
bool at_range_end(double value, double lo, double hi, bool periodic);

// Residual summaries of a stacked residual over the rows of `data`.
AxisRms axis_rms(const Eigen::VectorXd& residual, Eigen::Index samples);
std::vector<SegmentResidual> segment_residuals(const Measurement& data, const Eigen::VectorXd& residual);

}  // namespace mhb::pmsm

#pragma once
// Fitting the dynamic model (model/dynamic_model.hpp) to a raw log: the one-step-ahead prediction
// error of the currents, minimised over every free parameter by Levenberg-Marquardt from an
// equation-error start (docs/pmsm.md, "The dynamic model"); and the choice between the steady and
// the dynamic model for `--model-kind auto`.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "problems/pmsm/model/dynamic_model.hpp"

namespace mhb::pmsm {

struct DynamicFit {
    ModelSpec spec;
    std::vector<std::string> names, units;
    std::vector<bool> free;
    Eigen::VectorXd start;                // the equation-error start (all parameters)
    Eigen::VectorXd values;               // all parameters
    Eigen::VectorXd lower, upper;         // 95 % interval; the value when fixed, NaN when not determined
    Eigen::VectorXd standard_error;       // 0 when fixed, NaN when not determined
    Eigen::Index steps = 0;               // one-step predictions compared
    double time_step = 0.0;               // s, the log's median sampling step
    double time_constant = 0.0;           // s, min(L_d, L_q) / R_s of the fit
    Eigen::Vector2d rss{0.0, 0.0};        // A^2, current prediction error of i_d, i_q
    Eigen::Vector2d rms{0.0, 0.0};        // A
    int iterations = 0;                   // Levenberg-Marquardt iterations
    std::string method;
};

// Fits `spec`'s dynamic model to `data`. Throws InputError when the time column cannot be used
// (check_time_grid), an effect is not supported by the dynamic model, or the sampling is too slow
// for it (the equation-error start's electrical time constant under minimum_time_constant_steps steps).
DynamicFit fit_dynamic_model(const Measurement& data, const ModelSpec& spec, bool intervals = true);

// The equation-error start: the trapezoidal rule on L di/dt = u - f(i) over each step, which is
// linear in R_s, L_d, L_q, psi_f for fixed effect parameters (the effects' own values) and a delay
// tau, over the first `rows` steps (0: all). Biased (the current noise in the differences shrinks
// L_d, L_q), but in the basin of the fit.
Eigen::VectorXd dynamic_start(const DynamicModel& model, double tau, Eigen::Index rows = 0);

enum class ModelKind { Steady, Dynamic, Auto };
// "steady", "dynamic", "auto"; InputError naming --model-kind otherwise.
ModelKind parse_model_kind(const std::string& text);

// Which model `auto` uses on these data and why, in one sentence.
struct ModelKindChoice {
    ModelKind kind = ModelKind::Steady;
    std::string reason;
};
// The dynamic model when the log has a usable time column (strictly increasing, no gaps), every effect
// of `spec` is supported by it, it holds transients (at least 1 % of its rows outside the steady
// windows the moving-sum test finds, and at least 10), and its sampling resolves them (the
// equation-error estimate of min(L_d, L_q) / R_s is at least minimum_time_constant_steps steps).
ModelKindChoice choose_model_kind(const Measurement& data, const ModelSpec& spec);

std::string dynamic_fit_text(const DynamicFit& fit, const Measurement& data);
nlohmann::ordered_json dynamic_fit_json(const DynamicFit& fit);

}  // namespace mhb::pmsm

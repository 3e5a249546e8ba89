#include "problems/pmsm/fit/dynamic_fit.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/operating_points.hpp"
#include "problems/pmsm/report/fit_report.hpp"

namespace mhb::pmsm {

Eigen::VectorXd dynamic_start(const DynamicModel& model, double tau, Eigen::Index rows) {
    const Measurement& data = model.data();
    Eigen::VectorXd p = model.parameters_of(MotorParameters{});
    if (model.has_delay()) p[model.delay_index()] = tau;
    const Eigen::Index last = rows > 0 ? std::min(data.size() - 1, model.first_step() + rows) : data.size() - 1;
    const Eigen::VectorXd& t = *data.t;
    Eigen::Matrix4d gram = Eigen::Matrix4d::Zero();
    Eigen::Vector4d moment = Eigen::Vector4d::Zero();
    // Blocks of the steady model's affine split (its effects at their own values), one row of overlap.
    const Eigen::Index block = 512;
    AffinePrediction a;
    for (Eigen::Index first = model.first_step(); first < last; first += block) {
        const Eigen::Index n = std::min(block, last - first);
        if (a.rows() != n + 1) a = model.steady().make_affine(n + 1);
        model.steady().predict_affine(p.data(), a, first);
        for (Eigen::Index s = 0; s < n; ++s) {
            const Eigen::Index k = first + s;
            const double dt = t[k + 1] - t[k];
            const Eigen::Vector2d u = model.mean_input(k, tau);
            // Trapezoidal rule: L (i_{k+1} - i_k) / dt = u - (f(i_k) + f(i_{k+1})) / 2, f = offset + phi base.
            Eigen::Matrix<double, 2, 4> x;
            Eigen::Vector2d y;
            for (int j = 0; j < 4; ++j) {
                x(0, j) = 0.5 * (a.phi_d(s, j) + a.phi_d(s + 1, j));
                x(1, j) = 0.5 * (a.phi_q(s, j) + a.phi_q(s + 1, j));
            }
            x(0, 1) += (a.inputs.i_d[s + 1] - a.inputs.i_d[s]) / dt;
            x(1, 2) += (a.inputs.i_q[s + 1] - a.inputs.i_q[s]) / dt;
            y[0] = u[0] - 0.5 * (a.offset_d[s] + a.offset_d[s + 1]);
            y[1] = u[1] - 0.5 * (a.offset_q[s] + a.offset_q[s + 1]);
            gram += x.transpose() * x;
            moment += x.transpose() * y;
        }
    }
    // Column scaling: R_s is ohms and L henries; the pseudo-inverse leaves a column the data do not
    // determine at zero rather than at noise.
    const Eigen::Vector4d scale = gram.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::Matrix4d scaled = scale.asDiagonal() * gram * scale.asDiagonal();
    const Eigen::Vector4d base = scale.asDiagonal() * scaled.completeOrthogonalDecomposition().solve(scale.asDiagonal() * moment);
    const Bounds box = model.bounds();
    for (int j = 0; j < 4; ++j) p[j] = std::clamp(base[j], box.lower[j], box.upper[j]);
    return p;
}

namespace {

std::vector<std::string> units_of(const DynamicModel& model) {
    std::vector<std::string> units{"Ω", "H", "H", "Wb"};
    for (const auto& e : model.steady().effects())
        for (const auto& s : e->parameter_specs())
            if (s.type == ParameterType::Real) units.push_back(s.unit);
    if (model.has_delay()) units.push_back("s");
    return units;
}

double time_constant_of(const Eigen::VectorXd& p) { return std::min(p[1], p[2]) / p[0]; }

void require_resolved(const DynamicModel& model, const Eigen::VectorXd& start) {
    const double tc = time_constant_of(start);
    if (tc >= minimum_time_constant_steps * model.time_step()) return;
    throw InputError(model.data().source, 0, "t",
                     fmt::format("data rows 1 to {}: sampled every {:.6g} s, against an electrical time constant min(L_d, L_q) / R_s of "
                                 "{:.6g} s estimated from the log (L_d {:.4g} H, L_q {:.4g} H, R_s {:.4g} Ω): fewer than {:g} steps per time "
                                 "constant, too slow for the dynamic model (the currents settle within a step); use --model-kind steady",
                                 model.data().size(), model.time_step(), tc, start[1], start[2], start[0], minimum_time_constant_steps));
}

}  // namespace

DynamicFit fit_dynamic_model(const Measurement& data, const ModelSpec& spec, bool intervals) {
    DynamicModel model(data, spec);
    DynamicFit fit;
    fit.spec = spec;
    fit.names = model.parameter_names();
    fit.units = units_of(model);
    fit.free = model.free();
    fit.steps = model.steps();
    fit.time_step = model.time_step();
    // The start: the equation-error estimate, whose inductances are shrunk by the current noise in the
    // differences by as much as the log is steady (7 times on 2000 rows of the servo with 1 mA of noise
    // and one step), taken times 1, 2, 4, ... 64, and a free delay scanned at quarter steps over its
    // range (the prediction error has a narrow valley at the true delay, where the input's steps arrive
    // in the right sample); the best by the prediction error on about the first scan_steps steps, so
    // that the fit does not begin in the basin of a machine whose currents follow their voltage at once.
    const Eigen::Index scan_steps = 5000;
    {
        std::vector<double> delays{model.has_delay() ? model.parameters_of(MotorParameters{})[model.delay_index()] : 0.0};
        if (model.has_delay() && fit.free[static_cast<std::size_t>(model.delay_index())]) {
            delays.clear();
            const Eigen::Index j = model.delay_index();
            for (double tau = model.bounds().lower[j]; tau <= model.bounds().upper[j] + 1e-15; tau += 0.25 * model.time_step())
                delays.push_back(tau);
        }
        double best = std::numeric_limits<double>::infinity(), best_delay = delays.front(), best_factor = 1.0;
        for (const double tau : delays) {
            const Eigen::VectorXd estimate = dynamic_start(model, tau, scan_steps);
            for (double factor = 1.0; factor <= 64.0; factor *= 2.0) {
                Eigen::VectorXd candidate = estimate;
                for (int j = 1; j <= 2; ++j)
                    if (fit.free[static_cast<std::size_t>(j)]) candidate[j] = std::min(candidate[j] * factor, model.bounds().upper[j]);
                model.set_memory(time_constant_of(candidate));
                model.use_subset(scan_steps);
                const double rss = model.residual_sums(candidate).sum();
                if (rss < best) {
                    best = rss;
                    best_delay = tau;
                    best_factor = factor;
                }
            }
        }
        model.use_subset(0);
        fit.start = dynamic_start(model, best_delay);
        for (int j = 1; j <= 2; ++j)
            if (fit.free[static_cast<std::size_t>(j)]) fit.start[j] = std::min(fit.start[j] * best_factor, model.bounds().upper[j]);
    }

    std::vector<Eigen::Index> columns;
    for (Eigen::Index j = 0; j < model.parameter_count(); ++j)
        if (fit.free[static_cast<std::size_t>(j)]) columns.push_back(j);
    const auto p = static_cast<Eigen::Index>(columns.size());
    const Bounds& box = model.bounds();

    // Levenberg-Marquardt with Marquardt's scaling (the parameters span ohms to microseconds); steps
    // clipped to the box. Stops when a step gains less than 1e-10 of the sum of squares.
    Eigen::VectorXd x = fit.start;
    DynamicModel::NormalEquations equations;
    auto levenberg_marquardt = [&] {
        equations = model.normal_equations(x, columns);
        double rss = equations.rss[0] + equations.rss[1];
        double lambda = 1e-4;
        for (int iteration = 0; iteration < 100; ++iteration) {
            const Eigen::MatrixXd h_all = equations.gram[0] + equations.gram[1];
            const Eigen::VectorXd g_all = equations.moment[0] + equations.moment[1];
            // A parameter at a bound of its range that the gradient pushes outward is held this
            // iteration (a delay of zero at its lower bound): it would stop every step.
            std::vector<Eigen::Index> moving;
            for (Eigen::Index c = 0; c < p; ++c) {
                const Eigen::Index j = columns[static_cast<std::size_t>(c)];
                const bool held = (x[j] <= box.lower[j] && g_all[c] > 0.0) || (x[j] >= box.upper[j] && g_all[c] < 0.0);
                if (!held) moving.push_back(c);
            }
            const auto m = static_cast<Eigen::Index>(moving.size());
            if (m == 0) break;
            const Eigen::MatrixXd h = h_all(moving, moving);
            const Eigen::VectorXd g = g_all(moving);
            const Eigen::VectorXd d = h.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
            const Eigen::MatrixXd scaled = d.asDiagonal() * h * d.asDiagonal();
            // Done when the Gauss-Newton step would gain less than 1e-4 of the noise variance (the
            // parameters then within 1 % of a standard error of the optimum): no trial pass is spent.
            const Eigen::VectorXd scaled_gradient = d.asDiagonal() * g;
            const double predicted = scaled_gradient.dot(scaled.completeOrthogonalDecomposition().solve(scaled_gradient));
            if (predicted < 1e-4 * rss / static_cast<double>(std::max<Eigen::Index>(1, 2 * equations.steps))) break;
            bool improved = false;
            double gain = 0.0;
            for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
                Eigen::MatrixXd damped = scaled;
                damped.diagonal().array() += lambda;
                const Eigen::VectorXd step = -(d.asDiagonal() * damped.ldlt().solve(d.asDiagonal() * g)).eval();
                Eigen::VectorXd trial = x;
                for (Eigen::Index k = 0; k < m; ++k) {
                    const Eigen::Index j = columns[static_cast<std::size_t>(moving[static_cast<std::size_t>(k)])];
                    trial[j] = std::clamp(x[j] + step[k], box.lower[j], box.upper[j]);
                }
                const double trial_rss = model.residual_sums(trial).sum();
                if (trial_rss < rss) {
                    gain = rss - trial_rss;
                    x = trial;
                    rss = trial_rss;
                    lambda = std::max(lambda / 4.0, 1e-12);
                    improved = true;
                } else {
                    lambda *= 8.0;
                }
            }
            ++fit.iterations;
            if (!improved) break;
            equations = model.normal_equations(x, columns);
            rss = equations.rss[0] + equations.rss[1];
            if (gain < 1e-12 * rss) break;
        }
    };
    // The carried current's memory from the start's time constant; once more from the fit's when that
    // is longer (the start's inductances are shrunk by the noise in its current differences).
    // First on a subset of the steps (every k-th block, about subset_steps), then on all: the subset's
    // optimum is within its noise of the whole log's, so the last iterations on all rows are few.
    const Eigen::Index subset_steps = 50000;
    model.set_memory(time_constant_of(fit.start));
    if (model.steps() > 2 * subset_steps) {
        model.use_subset(subset_steps);
        levenberg_marquardt();
        model.set_memory(time_constant_of(x));
    }
    model.use_subset(0);
    levenberg_marquardt();
    const Eigen::Index warmup = model.warmup_steps();
    model.set_memory(time_constant_of(x));
    if (model.warmup_steps() > warmup) levenberg_marquardt();

    const Eigen::Index n = model.parameter_count();
    require_resolved(model, x);
    fit.values = x;
    fit.rss = {equations.rss[0], equations.rss[1]};
    const double steps = static_cast<double>(std::max<Eigen::Index>(fit.steps, 1));
    fit.rms = (fit.rss / steps).cwiseSqrt();
    fit.time_constant = time_constant_of(x);
    fit.lower = fit.upper = x;
    fit.standard_error = Eigen::VectorXd::Zero(n);
    fit.method = fmt::format("the dynamic model (exact zero-order hold at each step's speed, {}): prediction error of the current "
                             "carried from step to step, over {} steps of {:.6g} s; Levenberg-Marquardt from an equation-error start, "
                             "{} iterations",
                             model.has_delay() ? "the delay a fractional delay of the input" : "no delay", fit.steps, fit.time_step,
                             fit.iterations);
    if (!intervals || p == 0) return fit;
    // Sandwich covariance with one noise variance per axis: the one-step prediction errors of a right
    // model are the innovations, uncorrelated from step to step.
    const Eigen::MatrixXd h = equations.gram[0] + equations.gram[1];
    const double dof = std::max(1.0, 2.0 * steps - static_cast<double>(p));
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(p, p);
    for (int a = 0; a < 2; ++a) s += (equations.rss[a] / (0.5 * dof)) * equations.gram[a];
    const Eigen::MatrixXd inverse = h.completeOrthogonalDecomposition().pseudoInverse();
    const Eigen::MatrixXd covariance = inverse * s * inverse;
    for (Eigen::Index c = 0; c < p; ++c) {
        const Eigen::Index j = columns[static_cast<std::size_t>(c)];
        const double se = std::sqrt(std::max(0.0, covariance(c, c)));
        const bool determined = h(c, c) > 0.0 && std::isfinite(se);
        fit.standard_error[j] = determined ? se : std::numeric_limits<double>::quiet_NaN();
        fit.lower[j] = determined ? x[j] - 1.959963984540054 * se : std::numeric_limits<double>::quiet_NaN();
        fit.upper[j] = determined ? x[j] + 1.959963984540054 * se : std::numeric_limits<double>::quiet_NaN();
    }
    return fit;
}

ModelKind parse_model_kind(const std::string& text) {
    if (text == "steady") return ModelKind::Steady;
    if (text == "dynamic") return ModelKind::Dynamic;
    if (text == "auto") return ModelKind::Auto;
    throw InputError("command line", 0, "--model-kind", fmt::format("'{}': expected steady, dynamic or auto", text));
}

ModelKindChoice choose_model_kind(const Measurement& data, const ModelSpec& spec) {
    ModelKindChoice choice;
    const TimeGridCheck grid = check_time_grid(data);
    if (!grid.usable()) {
        choice.reason = fmt::format("steady: {}", grid.problem);
        return choice;
    }
    for (const auto& e : make_effects(spec)) {
        const std::string why = dynamic_model_unsupported(*e);
        if (!why.empty()) {
            choice.reason = fmt::format("steady: {}", why);
            return choice;
        }
    }
    const OperatingPoints points = find_operating_points(data);
    const Eigen::Index needed = std::max<Eigen::Index>(10, data.size() / 100);
    if (points.transient_rows < needed) {
        choice.reason = fmt::format("steady: the log holds no transients to speak of ({} of {} rows outside its steady windows, fewer than {})",
                                    points.transient_rows, data.size(), needed);
        return choice;
    }
    // The time constant of the fit itself: an equation-error estimate is shrunk by the current noise.
    double tc = 0.0;
    try {
        tc = fit_dynamic_model(data, spec, false).time_constant;
    } catch (const InputError& e) {
        choice.reason = fmt::format("steady: {}", e.message());
        return choice;
    }
    choice.kind = ModelKind::Dynamic;
    choice.reason = fmt::format("dynamic: the log is sampled without gaps every {:.6g} s, {} of its {} rows are transient, and the electrical "
                                "time constant estimated from it ({:.6g} s) is {:.3g} steps",
                                grid.step, points.transient_rows, data.size(), tc, tc / grid.step);
    return choice;
}

std::string dynamic_fit_text(const DynamicFit& fit, const Measurement& data) {
    std::string t = fmt::format("data: {} ({} samples)\n", data.source, data.size());
    t += fmt::format("model: {} (dynamic)\nfitted by {}\n\n", fit.spec.text(), fit.method);
    t += fmt::format("{:<28} {:>14} {:>36}  {}\n", "parameter", "value", "95 % interval", "unit");
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        const std::string interval = !fit.free[j]                        ? std::string("fixed")
                                     : !std::isfinite(fit.lower[k])      ? std::string("not determined")
                                                                         : fmt::format("[{}, {}]", value_text(fit.lower[k]), value_text(fit.upper[k]));
        t += fmt::format("{:<28} {:>14} {:>36}  {}\n", fit.names[j], value_text(fit.values[k]), interval, fit.units[j]);
    }
    t += fmt::format("\none-step current prediction error rms: i_d {:.4g} A, i_q {:.4g} A\n", fit.rms[0], fit.rms[1]);
    t += fmt::format("electrical time constant min(L_d, L_q) / R_s: {:.4g} s ({:.3g} sampling steps)\n", fit.time_constant,
                     fit.time_constant / fit.time_step);
    return t;
}

nlohmann::ordered_json dynamic_fit_json(const DynamicFit& fit) {
    nlohmann::ordered_json parameters = nlohmann::ordered_json::object();
    for (std::size_t j = 0; j < fit.names.size(); ++j) {
        const auto k = static_cast<Eigen::Index>(j);
        parameters[fit.names[j]] = {{"value", fit.values[k]},
                                    {"ci95", {finite_or_null(fit.lower[k]), finite_or_null(fit.upper[k])}},
                                    {"standard_error", finite_or_null(fit.standard_error[k])},
                                    {"unit", fit.units[j]},
                                    {"fixed", !fit.free[j]},
                                    {"start", fit.start[k]}};
    }
    return {{"model", fit.spec.text()},
            {"model_kind", "dynamic"},
            {"method", fit.method},
            {"steps", fit.steps},
            {"time_step", fit.time_step},
            {"time_constant", fit.time_constant},
            {"rms", {{"i_d", fit.rms[0]}, {"i_q", fit.rms[1]}}},
            {"iterations", fit.iterations},
            {"parameters", parameters}};
}

}  // namespace mhb::pmsm

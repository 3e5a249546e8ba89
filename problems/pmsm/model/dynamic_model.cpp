#include "problems/pmsm/model/dynamic_model.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cmath>
#include <complex>
#include <numbers>

#include <Eigen/LU>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "framework/input_error.hpp"

namespace mhb::pmsm {

ExponentialPair exponential_pair(const Eigen::Matrix2d& m) {
    const double norm = m.cwiseAbs().rowwise().sum().maxCoeff();
    int squarings = 0;
    double scaled_norm = norm;
    while (scaled_norm > 0.5 && squarings < 60) {
        scaled_norm *= 0.5;
        ++squarings;
    }
    const Eigen::Matrix2d x = std::ldexp(1.0, -squarings) * m;
    // Terms x^n / (n + 1)! of phi1 until the next one is below rounding: 0.5^(K+1)/(K+2)! < 1e-17 by K = 13.
    int degree = 1;
    for (double term = scaled_norm / 2.0; degree < 14 && term > 1e-17 * (1.0 + scaled_norm); ++degree)
        term *= scaled_norm / (degree + 2.0);
    // Horner: phi1(x) = I/1! + x (I/2! + x (I/3! + ...)).
    double factorial = 1.0;
    for (int n = 2; n <= degree + 1; ++n) factorial *= n;
    Eigen::Matrix2d p = Eigen::Matrix2d::Identity() / factorial;
    for (int n = degree - 1; n >= 0; --n) {
        factorial /= (n + 2.0);
        p = x * p;
        p.diagonal().array() += 1.0 / factorial;
    }
    Eigen::Matrix2d e = Eigen::Matrix2d::Identity() + x * p;
    for (int s = 0; s < squarings; ++s) {
        p = 0.5 * ((Eigen::Matrix2d::Identity() + e) * p).eval();
        e = (e * e).eval();
    }
    return {e, p};
}

ZeroOrderHoldStep zero_order_hold_step(double rs, const Eigen::Matrix2d& inductance, double omega, double dt) {
    const Eigen::Matrix2d inverse = inductance.inverse();
    Eigen::Matrix2d j;
    j << 0.0, -1.0, 1.0, 0.0;
    const Eigen::Matrix2d a = -inverse * (rs * Eigen::Matrix2d::Identity() + omega * j * inductance);
    const ExponentialPair e = exponential_pair(a * dt);
    return {e.exp, dt * e.integral * inverse};
}

TimeGridCheck check_time_grid(const Measurement& data) {
    TimeGridCheck check;
    if (!data.t) {
        check.problem = "the dynamic model needs the time column t, which the data lack";
        return check;
    }
    const Eigen::VectorXd& t = *data.t;
    if (t.size() < 3) {
        check.problem = "the dynamic model needs at least 3 rows";
        return check;
    }
    Eigen::VectorXd steps = t.tail(t.size() - 1) - t.head(t.size() - 1);
    for (Eigen::Index k = 0; k < steps.size(); ++k)
        if (!(steps[k] > 0.0)) {
            check.problem = fmt::format("data row {}: t = {:.9g} s does not increase (row {}: t = {:.9g} s); the dynamic model "
                                        "needs a strictly increasing time",
                                        k + 2, t[k + 1], k + 1, t[k]);
            check.row = k + 2;
            return check;
        }
    Eigen::VectorXd sorted = steps;
    std::nth_element(sorted.data(), sorted.data() + sorted.size() / 2, sorted.data() + sorted.size());
    check.step = sorted[sorted.size() / 2];
    for (Eigen::Index k = 0; k < steps.size(); ++k)
        if (steps[k] > time_gap_ratio * check.step) {
            check.problem = fmt::format("data row {}: a gap of {:.6g} s after t = {:.9g} s, {:.3g} times the median step {:.6g} s "
                                        "(more than {:g}: not one sampling step, e.g. settling left out of the log); the "
                                        "dynamic model needs a log sampled without gaps",
                                        k + 2, steps[k], t[k], steps[k] / check.step, check.step, time_gap_ratio);
            check.row = k + 2;
            return check;
        }
    return check;
}

std::string dynamic_model_unsupported(const Effect& effect) {
    const unsigned stages = effect.model_stages();
    if (acts_in(stages, ModelStage::FluxLinkage))
        return fmt::format("{} changes the flux linkage, so the inductance of a step is no longer L_d, L_q (its incremental "
                           "inductance is not yet part of the dynamic model)",
                           effect.name());
    if (acts_in(stages, ModelStage::ControllerFrame))
        return fmt::format("{} rotates the voltage between the machine and the log, so the inductive voltage is logged rotated "
                           "(not yet part of the dynamic model)",
                           effect.name());
    if (acts_in(stages, ModelStage::Delay) && effect.values().size() != 1)
        return fmt::format("{} acts as a delay but has not exactly one parameter (the delay in seconds)", effect.name());
    return {};
}

namespace {

// Which effect of the spec is the delay: the one acting in the Delay stage (-1: none).
int delay_effect_of(const std::vector<std::unique_ptr<Effect>>& effects) {
    for (std::size_t k = 0; k < effects.size(); ++k)
        if (acts_in(effects[k]->model_stages(), ModelStage::Delay)) return static_cast<int>(k);
    return -1;
}

std::atomic<std::uint64_t> next_model_id{1};

}  // namespace

Eigen::VectorXd step_speeds(const Measurement& data) {
    Eigen::VectorXd speed = data.omega_e;
    const Eigen::Index n = data.size();
    for (Eigen::Index k = 0; k + 1 < n; ++k) {
        speed[k] = data.omega_e[k + 1];
        if (!data.theta_e || !data.t) continue;
        const double dt = (*data.t)[k + 1] - (*data.t)[k];
        double turn = (*data.theta_e)[k + 1] - (*data.theta_e)[k];
        // The turn nearest to what the logged speed says, whatever the angle's wrapping.
        turn += 2.0 * std::numbers::pi * std::round((speed[k] * dt - turn) / (2.0 * std::numbers::pi));
        speed[k] = turn / dt;
    }
    return speed;
}

DynamicModel::DynamicModel(const Measurement& data, const ModelSpec& spec)
    : data_(data), grid_(check_time_grid(data)), id_(next_model_id++) {
    if (!grid_.usable()) throw InputError(data.source, 0, "t", grid_.problem);
    auto effects = make_effects(spec);
    for (const auto& e : effects) {
        const std::string why = dynamic_model_unsupported(*e);
        if (!why.empty()) throw InputError("--model", 0, e->name(), why + "; fit it with --model-kind steady");
    }
    const int delay = delay_effect_of(effects);
    ModelSpec inner = spec;
    std::unique_ptr<Effect> delay_effect;
    if (delay >= 0) {
        inner = spec.without(spec.effects[static_cast<std::size_t>(delay)].name);
        delay_effect = std::move(effects[static_cast<std::size_t>(delay)]);
    }
    steady_ = make_model(inner, data);
    // The predictor integrates L di/dt of the true current itself, the offset's ripple included.
    steady_->leave_out(ModelStage::CurrentRipple);
    step_speed_ = step_speeds(data);
    steady_->set_speed(&step_speed_);
    steady_count_ = steady_->parameter_count();
    names_ = steady_->parameter_names();
    free_ = free_parameters(inner);
    bounds_ = steady_->bounds();
    if (delay_effect) {
        const auto& term = spec.effects[static_cast<std::size_t>(delay)];
        const ParameterSpec* tau = nullptr;
        for (const auto& s : delay_effect->parameter_specs())
            if (s.type == ParameterType::Real) tau = &s;
        delay_ = steady_count_;
        names_.push_back(delay_effect->name() + "." + tau->name);
        free_.push_back(term.fixed.count(tau->name) == 0);
        bounds_.lower.conservativeResize(steady_count_ + 1);
        bounds_.upper.conservativeResize(steady_count_ + 1);
        bounds_.lower[steady_count_] = tau->minimum;
        bounds_.upper[steady_count_] = tau->maximum;
        // Rows before the first step: the longest delay the effect declares, plus the row a fraction reads.
        history_ = static_cast<Eigen::Index>(std::ceil(tau->maximum / grid_.step)) + 1;
        delay_start_ = delay_effect->values()[0];
    }
    // A handful of steps cannot tell five parameters apart; a log that short is a mistake.
    constexpr Eigen::Index fewest_steps = 20;
    if (steps() < fewest_steps)
        throw InputError(data.source, 0, "t",
                         fmt::format("{} rows give {} steps to predict{}; the dynamic model needs at least {}", data.size(), steps(),
                                     has_delay() ? fmt::format(" after the {} rows a delay of up to {:g} s reads", history_, bounds_.upper[delay_]) : "",
                                     fewest_steps));
}

Eigen::VectorXd DynamicModel::parameters_of(const MotorParameters& motor) const {
    Eigen::VectorXd p(parameter_count());
    p.head(steady_count_) = steady_->parameters_of(motor);
    if (has_delay()) p[delay_] = delay_start_;
    return p;
}

namespace {

// Per-thread arrays for one block of steps: the steady model's affine split over the block's rows
// (its warm-up, its steps and the row after them), once at the parameters and once per moved effect
// parameter.
struct BlockScratch {
    AffinePrediction at;
    std::vector<AffinePrediction> moved;
    Eigen::Index rows = -1;
};

// The voltage of the affine split at row j: offset + phi base.
inline Eigen::Vector2d affine_voltage(const AffinePrediction& a, Eigen::Index j, const double* base) {
    return {a.offset_d[j] + a.phi_d(j, 0) * base[0] + a.phi_d(j, 1) * base[1] + a.phi_d(j, 2) * base[2] + a.phi_d(j, 3) * base[3],
            a.offset_q[j] + a.phi_q(j, 0) * base[0] + a.phi_q(j, 1) * base[1] + a.phi_q(j, 2) * base[2] + a.phi_q(j, 3) * base[3]};
}

inline Eigen::Vector2d current(const AffinePrediction& a, Eigen::Index j) { return {a.inputs.i_d[j], a.inputs.i_q[j]}; }

// What drives one step: its length, speed and (delayed, rotated) input voltages.
struct StepInput {
    double dt = 0.0, omega = 0.0;
    bool delayed = false;
    double late_fraction = 1.0;            // share of the step under the later delayed sample
    Eigen::Vector2d early, late;           // delayed, rotated inputs (V); late = the logged u without delay
};

// The step's matrices at one (R_s, L_d, L_q): Phi, Gamma of the whole step, Gamma of its last
// late_fraction (with a delay).
struct StepGains {
    Eigen::Matrix2d phi, gamma, late;
};

inline StepGains step_gains(const StepInput& in, double rs, double ld, double lq) {
    const Eigen::Matrix2d inductance = Eigen::Vector2d(ld, lq).asDiagonal();
    const ZeroOrderHoldStep whole = zero_order_hold_step(rs, inductance, in.omega, in.dt);
    StepGains g{whole.phi, whole.gamma, Eigen::Matrix2d::Zero()};
    if (in.delayed) g.late = zero_order_hold_step(rs, inductance, in.omega, in.late_fraction * in.dt).gamma;
    return g;
}

// d(Phi, Gamma, Gamma_late) / d(R_s, L_d or L_q: parameter j = 0, 1, 2) from the cubic Taylor series
// of the step (Phi = I + M + M^2/2 + M^3/6, Gamma = dt (I + M/2 + M^2/6 + M^3/24) L^-1, M = A dt):
// for the Jacobian only, where its relative error ~|M|^4/24 (7e-5 at the servo's |M| = 0.2) slows
// Gauss-Newton by as little, while the prediction itself stays exact. Three exponentials per row
// fewer than differences of the exact step.
inline Eigen::Matrix2d taylor_derivative(const Eigen::Matrix2d& m, const Eigen::Matrix2d& dm, const double c[4]) {
    const Eigen::Matrix2d m2 = m * m;
    return c[1] * dm + c[2] * (dm * m + m * dm) + c[3] * (dm * m2 + m * dm * m + m2 * dm);
}

inline Eigen::Matrix2d taylor(const Eigen::Matrix2d& m, const double c[4]) {
    return c[0] * Eigen::Matrix2d::Identity() + c[1] * m + c[2] * m * m + c[3] * m * m * m;
}

inline StepGains step_gains_derivative(const StepInput& in, double rs, double ld, double lq, int j) {
    const double w = in.omega;
    Eigen::Matrix2d a, da, inverse = Eigen::Vector2d(1.0 / ld, 1.0 / lq).asDiagonal(), dinverse = Eigen::Matrix2d::Zero();
    a << -rs / ld, w * lq / ld, -w * ld / lq, -rs / lq;
    if (j == 0) {
        da << -1.0 / ld, 0.0, 0.0, -1.0 / lq;
    } else if (j == 1) {
        da << rs / (ld * ld), -w * lq / (ld * ld), -w / lq, 0.0;
        dinverse(0, 0) = -1.0 / (ld * ld);
    } else {
        da << 0.0, w / ld, w * ld / (lq * lq), rs / (lq * lq);
        dinverse(1, 1) = -1.0 / (lq * lq);
    }
    static constexpr double exp_terms[4] = {1.0, 1.0, 0.5, 1.0 / 6.0};
    static constexpr double phi1_terms[4] = {1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0};
    auto gamma_derivative = [&](double dt) {
        const Eigen::Matrix2d m = a * dt, dm = da * dt;
        return Eigen::Matrix2d(dt * (taylor_derivative(m, dm, phi1_terms) * inverse + taylor(m, phi1_terms) * dinverse));
    };
    StepGains d;
    d.phi = taylor_derivative(a * in.dt, da * in.dt, exp_terms);
    d.gamma = gamma_derivative(in.dt);
    d.late = in.delayed ? gamma_derivative(in.late_fraction * in.dt) : Eigen::Matrix2d::Zero();
    return d;
}

// The predicted current after the step from the model's own current x, the logged current i and the
// steady model's voltage f at it: i + Gamma (u - f) + Phi (x - i), i.e. the exact step from i carried
// over to x through the step's linear part (f(x) = f(i) + (R_s + omega J L)(x - i)).
inline Eigen::Vector2d step(const StepInput& in, const StepGains& g, const Eigen::Vector2d& f, const Eigen::Vector2d& i,
                            const Eigen::Vector2d& x) {
    const Eigen::Vector2d drive = in.delayed ? Eigen::Vector2d((g.gamma - g.late) * in.early + g.late * in.late - g.gamma * f)
                                             : Eigen::Vector2d(g.gamma * (in.late - f));
    return i + drive + g.phi * (x - i);
}

}  // namespace

Eigen::Index DynamicModel::warmup_steps() const { return warmup_; }

void DynamicModel::use_subset(Eigen::Index steps) {
    block_stride_ = 1;
    if (steps > 0) block_stride_ = std::max<Eigen::Index>(1, blocks() / std::max<Eigen::Index>(1, steps / block_steps_));
}

void DynamicModel::set_memory(double time_constant) {
    // The carried state forgets its start as e^{-t / time_constant}: 40 time constants are e^{-40}, below
    // rounding of what a step adds.
    const double steps = 40.0 * std::max(time_constant, 0.0) / grid_.step;
    warmup_ = static_cast<Eigen::Index>(std::clamp(std::ceil(steps), 8.0, 1e5));
    block_steps_ = std::max<Eigen::Index>(512, 4 * warmup_);
}

void DynamicModel::block(const Eigen::VectorXd& p, const std::vector<Eigen::Index>& columns, Eigen::Index b, Eigen::ArrayXd& r_d,
                         Eigen::ArrayXd& r_q, Eigen::MatrixXd* j_d, Eigen::MatrixXd* j_q) const {
    const Eigen::Index first_step = history_ + b * block_steps_;
    const Eigen::Index n = std::min(block_steps_, steps() - b * block_steps_);
    // The model's current is carried from `warm` steps before the block (from the logged current there),
    // the same steps the block before predicts: its start is forgotten by the block's first step.
    const Eigen::Index warm = std::min(warmup_, first_step - history_);
    const Eigen::Index first_row = first_step - warm;
    const Eigen::Index rows = warm + n + 1;
    const auto cols = static_cast<Eigen::Index>(columns.size());
    std::vector<Eigen::Index> effect_columns;
    for (Eigen::Index c = 0; c < cols; ++c)
        if (columns[static_cast<std::size_t>(c)] >= 4) effect_columns.push_back(c);
    // This thread's arrays, remade when another model or another block length last used them.
    thread_local BlockScratch scratch;
    thread_local std::uint64_t owner = 0;
    if (owner != id_ || scratch.rows != rows) {
        scratch.at = steady_->make_affine(rows);
        scratch.moved.clear();
        scratch.rows = rows;
        owner = id_;
    }
    while (scratch.moved.size() < effect_columns.size()) scratch.moved.push_back(steady_->make_affine(rows));
    steady_->predict_affine(p.data(), scratch.at, first_row);
    const AffinePrediction& a = scratch.at;
    const double tau = has_delay() ? p[delay_] : 0.0;
    const Eigen::VectorXd& t = *data_.t;

    auto input_of = [&](Eigen::Index k, double delay) {
        StepInput in;
        in.dt = t[k + 1] - t[k];
        in.omega = step_speed_[k];
        if (!has_delay()) {
            in.late = {data_.u_d[k], data_.u_q[k]};
            return in;
        }
        const double samples = delay / grid_.step;
        const auto m = static_cast<Eigen::Index>(std::floor(samples));
        const double fraction = samples - static_cast<double>(m);
        const std::complex<double> turn = std::polar(1.0, -in.omega * delay);
        const std::complex<double> late = turn * std::complex<double>(data_.u_d[k - m], data_.u_q[k - m]);
        const std::complex<double> early = turn * std::complex<double>(data_.u_d[k - m - 1], data_.u_q[k - m - 1]);
        in.delayed = true;
        in.late_fraction = 1.0 - fraction;
        in.late = {late.real(), late.imag()};
        in.early = {early.real(), early.imag()};
        return in;
    };

    // Effect parameters: the block's affine split again at each moved value (a delay moves only the input).
    std::vector<double> moved_step(static_cast<std::size_t>(cols), 0.0);
    std::vector<Eigen::VectorXd> moved_parameters(effect_columns.size());
    for (std::size_t e = 0; e < effect_columns.size(); ++e) {
        const Eigen::Index c = effect_columns[e];
        const Eigen::Index j = columns[static_cast<std::size_t>(c)];
        const double h = 1e-6 * (bounds_.upper[j] - bounds_.lower[j]);
        moved_parameters[e] = p;
        moved_parameters[e][j] += p[j] + h > bounds_.upper[j] ? -h : h;
        moved_step[static_cast<std::size_t>(c)] = moved_parameters[e][j] - p[j];
        steady_->predict_affine(moved_parameters[e].data(), scratch.moved[e], first_row);
    }

    r_d.resize(n);
    r_q.resize(n);
    if (j_d) {
        j_d->resize(n, cols);
        j_q->resize(n, cols);
    }
    const double* base = p.data();
    Eigen::Vector2d x = current(a, 0);
    // Sensitivities dx/dp of the carried current, one column per listed parameter.
    Eigen::Matrix<double, 2, Eigen::Dynamic> sensitivity = Eigen::Matrix<double, 2, Eigen::Dynamic>::Zero(2, j_d ? cols : 0);
    Eigen::Matrix<double, 2, Eigen::Dynamic> direct(2, j_d ? cols : 0);
    if (j_d)
        for (std::size_t e = 0; e < effect_columns.size(); ++e) {
            const Eigen::Index c = effect_columns[e];
            sensitivity.col(c) = (current(scratch.moved[e], 0) - x) / moved_step[static_cast<std::size_t>(c)];
        }
    for (Eigen::Index s = 0; s < warm + n; ++s) {
        const Eigen::Index k = first_row + s;
        const StepInput in = input_of(k, tau);
        const StepGains g = step_gains(in, base[0], base[1], base[2]);
        const Eigen::Vector2d i = current(a, s), f = affine_voltage(a, s, base);
        const Eigen::Vector2d next = step(in, g, f, i, x);
        if (j_d) {
            for (Eigen::Index c = 0; c < cols; ++c) {
                const Eigen::Index j = columns[static_cast<std::size_t>(c)];
                if (j >= 4) continue;
                // f is affine in the base parameters: d f / d p_j = phi_j exactly.
                direct.col(c) = -(g.gamma * Eigen::Vector2d(a.phi_d(s, j), a.phi_q(s, j)));
                if (j < 3) direct.col(c) += step(in, step_gains_derivative(in, base[0], base[1], base[2], static_cast<int>(j)), f, i, x) - i;
            }
            for (std::size_t e = 0; e < effect_columns.size(); ++e) {
                const Eigen::Index c = effect_columns[e];
                const AffinePrediction& m = scratch.moved[e];
                const Eigen::VectorXd& q = moved_parameters[e];
                // A moved delay moves the step's split, and so its gains.
                const bool delay = has_delay() && columns[static_cast<std::size_t>(c)] == delay_;
                const StepInput moved_in = delay ? input_of(k, q[delay_]) : in;
                const StepGains moved_gains = delay ? step_gains(moved_in, base[0], base[1], base[2]) : g;
                direct.col(c) = (step(moved_in, moved_gains, affine_voltage(m, s, q.data()), current(m, s), x) - next) /
                                moved_step[static_cast<std::size_t>(c)];
            }
            sensitivity = (direct + g.phi * sensitivity).eval();
        }
        x = next;
        if (s < warm) continue;
        const Eigen::Index out = s - warm;
        const Eigen::Vector2d measured = current(a, s + 1);
        r_d[out] = measured[0] - x[0];
        r_q[out] = measured[1] - x[1];
        if (!j_d) continue;
        // r = i - x: dr/dp = di/dp (sensor effects move the logged current) - dx/dp.
        for (Eigen::Index c = 0; c < cols; ++c) {
            (*j_d)(out, c) = -sensitivity(0, c);
            (*j_q)(out, c) = -sensitivity(1, c);
        }
        for (std::size_t e = 0; e < effect_columns.size(); ++e) {
            const Eigen::Index c = effect_columns[e];
            const Eigen::Vector2d moved = (current(scratch.moved[e], s + 1) - measured) / moved_step[static_cast<std::size_t>(c)];
            (*j_d)(out, c) += moved[0];
            (*j_q)(out, c) += moved[1];
        }
    }
}

Eigen::Vector2d DynamicModel::mean_input(Eigen::Index k, double tau) const {
    if (!has_delay()) return {data_.u_d[k], data_.u_q[k]};
    const double samples = tau / grid_.step;
    const auto m = static_cast<Eigen::Index>(std::floor(samples));
    const double fraction = samples - static_cast<double>(m);
    const std::complex<double> u = std::polar(1.0, -step_speed_[k] * tau) *
                                   ((1.0 - fraction) * std::complex<double>(data_.u_d[k - m], data_.u_q[k - m]) +
                                    fraction * std::complex<double>(data_.u_d[k - m - 1], data_.u_q[k - m - 1]));
    return {u.real(), u.imag()};
}

DynamicModel::NormalEquations DynamicModel::normal_equations(const Eigen::VectorXd& p, const std::vector<Eigen::Index>& columns) const {
    const auto cols = static_cast<Eigen::Index>(columns.size());
    const Eigen::Index used = (blocks() + block_stride_ - 1) / block_stride_;
    std::vector<NormalEquations> per_block(static_cast<std::size_t>(used));
    tbb::parallel_for(Eigen::Index{0}, used, [&](Eigen::Index u) {
        Eigen::ArrayXd r_d, r_q;
        Eigen::MatrixXd j_d, j_q;
        block(p, columns, u * block_stride_, r_d, r_q, &j_d, &j_q);
        NormalEquations& e = per_block[static_cast<std::size_t>(u)];
        e.gram[0] = j_d.transpose() * j_d;
        e.gram[1] = j_q.transpose() * j_q;
        e.moment[0] = j_d.transpose() * r_d.matrix();
        e.moment[1] = j_q.transpose() * r_q.matrix();
        e.rss[0] = r_d.square().sum();
        e.rss[1] = r_q.square().sum();
        e.steps = r_d.size();
    });
    NormalEquations sum;
    for (int a = 0; a < 2; ++a) {
        sum.gram[a] = Eigen::MatrixXd::Zero(cols, cols);
        sum.moment[a] = Eigen::VectorXd::Zero(cols);
    }
    for (const auto& e : per_block)
        for (int a = 0; a < 2; ++a) {
            sum.gram[a] += e.gram[a];
            sum.moment[a] += e.moment[a];
            sum.rss[a] += e.rss[a];
        }
    for (const auto& e : per_block) sum.steps += e.steps;
    return sum;
}

Eigen::Vector2d DynamicModel::residual_sums(const Eigen::VectorXd& p) const {
    const Eigen::Index used = (blocks() + block_stride_ - 1) / block_stride_;
    std::vector<Eigen::Vector2d> per_block(static_cast<std::size_t>(used));
    tbb::parallel_for(Eigen::Index{0}, used, [&](Eigen::Index u) {
        Eigen::ArrayXd r_d, r_q;
        block(p, {}, u * block_stride_, r_d, r_q, nullptr, nullptr);
        per_block[static_cast<std::size_t>(u)] = {r_d.square().sum(), r_q.square().sum()};
    });
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    for (const auto& s : per_block) sum += s;
    return sum;
}

void DynamicModel::predict(const Eigen::VectorXd& p, Eigen::VectorXd& predicted_d, Eigen::VectorXd& predicted_q,
                           Eigen::VectorXd& measured_d, Eigen::VectorXd& measured_q) const {
    const Eigen::Index n = steps();
    predicted_d.resize(n);
    predicted_q.resize(n);
    measured_d.resize(n);
    measured_q.resize(n);
    tbb::parallel_for(Eigen::Index{0}, blocks(), [&](Eigen::Index b) {
        Eigen::ArrayXd r_d, r_q;
        block(p, {}, b, r_d, r_q, nullptr, nullptr);
        // The measured currents of the block's rows after the sensor stages, which block() left in
        // this thread's scratch.
        AffinePrediction a = steady_->make_affine(r_d.size() + 1);
        steady_->predict_affine(p.data(), a, history_ + b * block_steps_);
        for (Eigen::Index s = 0; s < r_d.size(); ++s) {
            const Eigen::Index out = b * block_steps_ + s;
            measured_d[out] = a.inputs.i_d[s + 1];
            measured_q[out] = a.inputs.i_q[s + 1];
            predicted_d[out] = measured_d[out] - r_d[s];
            predicted_q[out] = measured_q[out] - r_q[s];
        }
    });
}

}  // namespace mhb::pmsm

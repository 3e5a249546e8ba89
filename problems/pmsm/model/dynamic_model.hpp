#pragma once
// The dynamic model: the seed paper's eq. (1), L di/dt = u - (R_s i + omega J psi) with the effects,
// as a one-step-ahead predictor of the current from the exact zero-order-hold discretisation of the dq
// model at each step's speed (step_speeds; docs/pmsm.md, "The dynamic model").
//
// The effects state their term once, in the steady-state model: at the logged currents i_k, the
// steady-state model of the same effects (without the delay, and without the stage that stands in
// for the L di/dt of a ripple the sensors' errors put on the true currents) predicts the voltage
// f(i_k) the machine needs when the currents do not change, every effect contributing through its
// stages. What the
// inverter applies beyond f drives the currents through the inductance:
//   L di/dt = u(t) - f(i),   f(i) ~ f(i_k) + (R_s + omega J L)(i - i_k) over the step,
//   i_{k+1} = i_k + Gamma_k (u_k - f(i_k)),   Gamma_k = dt phi1(A_k dt) L^-1,   A_k = -L^-1 (R_s + omega_k J L),
// omega_k the speed over the step (f is evaluated at it too),
// with phi1(M) = int_0^1 e^{M s} ds. For the base model f is linear in i and this is exactly
// i_{k+1} = Phi_k i_k + Gamma_k (u_k - omega_k J psi_f e_d), Phi_k = e^{A_k dt}; with effects it is the
// exponential (Rosenbrock) Euler step, whose only approximation is holding the effects' own voltage at
// its value at i_k over the step.
//
// The predictor carries its own current x from step to step rather than restarting from the logged one:
//   x_{k+1} = i_k + Gamma_k (u_k - f(i_k)) + Phi_k (x_k - i_k)
// (the step above from i_k, moved to x_k through the step's linear part). For the base model this is
// x_{k+1} = Phi_k x_k + Gamma_k (u_k - omega_k J psi_f e_d): the logged currents, and their sensor
// noise, enter only through the effects' own voltage. The prediction error i_{k+1} - x_{k+1} is then
// the sensor noise at the true parameters, uncorrelated with the prediction even in closed loop; a
// predictor restarted from each noisy logged current takes that noise as a regressor and shrinks
// L_d, L_q (measured: to 40-70 % on the servo with 1 mA of current noise). This is the Kalman
// predictor of a model whose noise is all at the sensors (gain 0). Its memory is the electrical time
// constant, so blocks of steps are evaluated in parallel, each carried from 40 time constants before it.
//
// The delay effect (the one effect acting in ModelStage::Delay) is a delay of the input voltage here:
// the inverter applies, in the rotor frame, e^{-j omega tau} times the logged command of tau earlier,
// the command held in dq between samples; with tau = (m + f) T_s the step's input is u_{k-m-1} for its
// first f T_s and u_{k-m} for the rest, split exactly (Gamma_late = (1 - f) dt phi1(A (1 - f) dt) L^-1,
// Gamma_early = Gamma - Gamma_late).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/model/model_spec.hpp"

namespace mhb::pmsm {

// e^{M} and phi1(M) = int_0^1 e^{M s} ds of a 2 x 2 matrix: Taylor series of phi1 (exp M = I + M phi1(M))
// after scaling M to norm <= 1/2, then squaring back (phi1(2X) = (I + e^X) phi1(X) / 2). Accurate to
// rounding for any M; about a hundred flops for the |M| <= 1/2 of a sampled drive.
struct ExponentialPair {
    Eigen::Matrix2d exp, integral;
};
ExponentialPair exponential_pair(const Eigen::Matrix2d& m);

// The zero-order-hold step of L di/dt = u - (R_s i + omega J L i) over dt, with a constant inductance
// matrix L (A = -L^-1 (R_s + omega J L)): i(dt) = phi i(0) + gamma u.
struct ZeroOrderHoldStep {
    Eigen::Matrix2d phi, gamma;
};
ZeroOrderHoldStep zero_order_hold_step(double rs, const Eigen::Matrix2d& inductance, double omega, double dt);

// What the time column allows: its median step (s) and, when the dynamic model cannot use the log,
// why, with the row (counted from 1, as a file's data rows) where it shows.
struct TimeGridCheck {
    double step = 0.0;      // median of t[k+1] - t[k]
    std::string problem;    // empty: usable
    Eigen::Index row = 0;   // the data row of the problem (from 1); 0 when it is not one row's
    bool usable() const { return problem.empty(); }
};
// A step this much longer than the median is a gap (e.g. a steady log's unlogged settling between
// segments): the currents across it are not one step of the model.
inline constexpr double time_gap_ratio = 1.5;
TimeGridCheck check_time_grid(const Measurement& data);

// The electrical time constant min(L_d, L_q) / R_s must be at least this many sampling steps for the
// dynamic model: faster, the currents settle within a step and the transients are not resolved.
inline constexpr double minimum_time_constant_steps = 2.0;

// The electrical speed over the step from each row to the next (rad/s): the logged angle's turn over
// the step divided by its length when the log has theta_e and t, else the speed logged at the step's
// end. A drive's speed is the encoder's angle difference over the period before its sample, so the
// speed logged at a row is the mean over the step before it, not after (tested: taking the row's own
// speed biased L_q by 0.8 % on a noise-free raw log of a drive accelerating from standstill). The last
// row keeps its logged speed.
Eigen::VectorXd step_speeds(const Measurement& data);

// Whether the dynamic model can represent this effect; empty when it can, else why not.
std::string dynamic_model_unsupported(const Effect& effect);

class DynamicModel {
public:
    // Throws InputError naming the file, the row and t when the time column is missing or cannot be
    // used (check_time_grid), and naming --model when an effect is not supported by the dynamic model.
    // Refers to `data`, which must outlive it.
    DynamicModel(const Measurement& data, const ModelSpec& spec);

    const Measurement& data() const { return data_; }
    // The steady-state model of the spec's effects less the delay: what states every effect's term.
    const SteadyStateModel& steady() const { return *steady_; }
    // The steady model's parameters, then "delay.tau" when the spec has a delay.
    const std::vector<std::string>& parameter_names() const { return names_; }
    Eigen::Index parameter_count() const { return static_cast<Eigen::Index>(names_.size()); }
    const std::vector<bool>& free() const { return free_; }
    const Bounds& bounds() const { return bounds_; }
    bool has_delay() const { return delay_ >= 0; }
    Eigen::Index delay_index() const { return delay_; }
    // Start values: the effects' own (fixed or default) values, base parameters of `motor`.
    Eigen::VectorXd parameters_of(const MotorParameters& motor) const;
    double time_step() const { return grid_.step; }

    // The steps predicted: row k to row k + 1 for k in [first_step(), data().size() - 1). The first
    // rows are left as the history a delay of up to the delay effect's largest declared value reads.
    Eigen::Index first_step() const { return history_; }
    Eigen::Index steps() const { return std::max<Eigen::Index>(0, data_.size() - 1 - history_); }

    // The step's input averaged over it (V, rotor frame): the logged u_k without a delay; with a delay
    // tau, the delayed, rotated samples weighted by their shares of the step. For start values.
    Eigen::Vector2d mean_input(Eigen::Index k, double tau) const;

    // One-step-ahead predicted currents (after the sensor stages: the rotor frame) of rows
    // first_step() + 1 .. n - 1, and the measured ones they are compared with, at parameters p.
    void predict(const Eigen::VectorXd& p, Eigen::VectorXd& predicted_d, Eigen::VectorXd& predicted_q,
                 Eigen::VectorXd& measured_d, Eigen::VectorXd& measured_q) const;

    // The predictor linearised at p in the listed parameters and reduced over all steps: per axis
    // (0: d, 1: q) J_a' J_a, J_a' r_a and r_a' r_a, r = measured - predicted current, J = dr/dp. Base
    // columns: exact in psi_f and in the steady model's affine split, forward differences of the step
    // matrices in R_s, L_d, L_q; effect columns by forward differences (1e-6 of the declared range).
    // Blocks of steps in parallel, summed in block order: the same numbers on any number of threads.
    struct NormalEquations {
        Eigen::MatrixXd gram[2];
        Eigen::VectorXd moment[2];
        double rss[2] = {0.0, 0.0};
        Eigen::Index steps = 0;  // steps summed
    };
    NormalEquations normal_equations(const Eigen::VectorXd& p, const std::vector<Eigen::Index>& columns) const;
    // r' r per axis only.
    Eigen::Vector2d residual_sums(const Eigen::VectorXd& p) const;

    // How long the carried current remembers its start: the electrical time constant (s) of the
    // parameters the model will be evaluated near. Sets how many steps before each block of steps the
    // carried current starts (40 time constants, at least 8), and the blocks' length (at least 512 steps
    // and four warm-ups). Until set, 8 steps.
    void set_memory(double time_constant);
    Eigen::Index warmup_steps() const;
    // normal_equations and residual_sums on about `steps` steps only, every k-th block of steps (each
    // still carried from its own warm-up), so that a fit's first iterations do not grow with the log;
    // 0: all steps (the default). Blocks are fixed by set_memory, so call this after it.
    void use_subset(Eigen::Index steps);

private:
    // Residuals of the steps of block b at p into r_d, r_q (and, with `columns`, the Jacobian rows).
    void block(const Eigen::VectorXd& p, const std::vector<Eigen::Index>& columns, Eigen::Index b, Eigen::ArrayXd& r_d,
               Eigen::ArrayXd& r_q, Eigen::MatrixXd* j_d, Eigen::MatrixXd* j_q) const;
    Eigen::Index blocks() const { return (steps() + block_steps_ - 1) / block_steps_; }

    const Measurement& data_;
    TimeGridCheck grid_;
    std::unique_ptr<SteadyStateModel> steady_;
    Eigen::VectorXd step_speed_;  // rad/s: the speed over the step from each row (the last row's its own)
    std::vector<std::string> names_;
    std::vector<bool> free_;
    Bounds bounds_;
    Eigen::Index delay_ = -1;  // index of delay.tau, -1 without a delay
    Eigen::Index history_ = 0;
    Eigen::Index steady_count_ = 0;  // parameters of the steady model
    double delay_start_ = 0.0;       // the delay effect's own value of tau
    std::uint64_t id_ = 0;           // tells this model's per-thread scratch from another's
    Eigen::Index warmup_ = 8, block_steps_ = 512;  // set_memory
    Eigen::Index block_stride_ = 1;                 // use_subset
};

}  // namespace mhb::pmsm

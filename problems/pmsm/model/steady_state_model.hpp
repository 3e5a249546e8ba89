#pragma once
// The steady-state voltage model: the base model of seed eq. (2),
//   u_d = R_s i_d - omega L_q i_q,   u_q = R_s i_q + omega L_d i_d + omega psi_f,
// with any chosen effects applied stage by stage (effects/effect.hpp). Parameters are the four base
// parameters followed by each effect's real parameters in declaration order.
#include <algorithm>
#include <complex>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "framework/problem.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {

// Table 2 of the seed: the search box of the base parameters Rs, Ld, Lq, psi_f.
Bounds base_parameter_bounds();
inline const std::vector<std::string> base_parameter_names{"Rs", "Ld", "Lq", "psi_f"};

// The scale of the logged currents and flux linkages (Effect::scale()): the largest current amplitude,
// and the largest |u| / |omega| over the rows whose speed is at least a tenth of the largest.
OperatingScale operating_scale_of(const Measurement& data);

// Throws InputError when `data` lacks a column the effect's model side needs.
void require_columns(const Effect& effect, const Measurement& data);

// The prediction split over a block of rows: u = offset + phi * (Rs, Ld, Lq, psi_f), for the effect
// parameters it was made with (SteadyStateModel::predict_affine).
struct AffinePrediction {
    // The block after the stages before the base parameters (sensors): its currents, speed, angle and
    // temperatures. The later stages run on `lane`, a copy, where an effect's later stages may change
    // those (Effect::model_changes_inputs), and on `inputs` itself otherwise (`lane` then empty).
    ModelState inputs;
    ModelState lane;
    Eigen::ArrayXd offset_d, offset_q;  // V: the prediction with the base parameters at zero
    Eigen::ArrayXXd phi_d, phi_q;       // V per unit of each base parameter (rows x 4)
    Eigen::VectorXd parameters;         // scratch: all parameters with the base ones replaced
    Eigen::ArrayXd residual_d, residual_q;  // scratch for whoever reduces the block

    Eigen::Index rows() const { return offset_d.size(); }
};

// A drive's current loop as the models of its log see it: an IMC-tuned PI of bandwidth alpha per
// axis (K_p = alpha L, K_i = alpha R) with the feed-forward of j omega L i on the measured current,
// computing once a control period from the sampled current and applying its output over the next.
struct CurrentLoop {
    double alpha = 0.0;   // rad/s: 2 pi times the bandwidth
    double period = 0.0;  // s: the control period
    // 1/s: R / L_d and R / L_q, the corners of the PI's integral and of the machine's own decay.
    double corner_d = 0.0, corner_q = 0.0;
    // Without both corners (a machine without resistance, or not known) the loop is proportional:
    // no integral, and the machine's own decay left out with it.
    bool integral() const { return corner_d > 0.0 && corner_q > 0.0; }
    double integral_corner_d() const { return integral() ? corner_d : 0.0; }
    double integral_corner_q() const { return integral() ? corner_q : 0.0; }
};

// What a control period does to the flux the loop leaves, x = L i (d, q) at speed omega with the
// voltage b held: x(T) = phi x(0) + gamma b, exact (dx/dt = A x + b, A = [[-c_d, omega],
// [-omega, -c_q]]: the turning of the rotor frame and, with the loop's integral, the decay at the
// corners).
struct LoopPeriod {
    double phi[2][2];
    double gamma[2][2];
};
LoopPeriod loop_period(const CurrentLoop& loop, double omega);

// What the loop puts into its logged reference of an effect's voltage, in time: `w_d`, `w_q` hold the
// voltage the effect takes from the machine (its law's value) at consecutive rows, and on return what
// the logged reference holds of it beyond what the current it leaves carries through the
// steady-state model (which predicts each row from the row's own current, so R i + j omega L i of
// that current is in it already). `steps[r]` counts the control periods from row r - 1 to row r
// (0: row r starts a run, taken at the loop's steady state, where the reference holds the whole law),
// `omega` is each row's electrical speed. Over a period the law is its mean on the line between the
// rows' values. Written in the flux the loop leaves, L i, the inductances enter only through the
// corners. docs/diagnosis.md, section 8. Every period is `period` (loop_period at the speed of the
// rows' operating point: a model passes one operating point's run at a time). `left_d`, `left_q`,
// when given, receive x at each row's sample.
void pass_through_current_loop(const CurrentLoop& loop, const LoopPeriod& period, const double* omega, const std::uint8_t* steps,
                               double* w_d, double* w_q, Eigen::Index n, double* left_d = nullptr, double* left_q = nullptr);

class SteadyStateModel {
public:
    // Rows per block: 512 rows of a model's ~20 per-sample arrays (80 kB) stay in the L2 cache.
    static constexpr Eigen::Index block_rows = 512;

    // Throws InputError when an effect needs a column the data lack.
    // The model refers to `data`, which must outlive it (a long log is not copied).
    SteadyStateModel(const Measurement& data, std::vector<std::unique_ptr<Effect>> effects);
    // The model keeps `data`.
    SteadyStateModel(Measurement&& data, std::vector<std::unique_ptr<Effect>> effects);
    SteadyStateModel(const SteadyStateModel&) = delete;
    SteadyStateModel& operator=(const SteadyStateModel&) = delete;

    const Measurement& data() const { return data_; }
    // Models of the same data share what they compute from them alike (the operating scale, the cos
    // and sin of the angle) while any of them exists; this handle keeps them for models made while it
    // lives, so that models made one after another do not each make them again. `data` must neither
    // change nor go while it is held.
    static std::shared_ptr<const void> hold_shared_tables(const Measurement& data);
    // Evaluates the model at these speeds instead of the logged omega_e (one per row; nullptr: the
    // logged ones). The dynamic model predicts a step at the speed over the step, not at its first row.
    // `speed` must outlive the model.
    void set_speed(const Eigen::VectorXd* speed) { speed_ = speed; }
    // Runs no effect at this stage: the dynamic model has its own L di/dt, so it leaves out the
    // steady state's stand-in for a ripple's (ModelStage::CurrentRipple).
    void leave_out(ModelStage stage) { stages_ &= ~static_cast<unsigned>(stage); }
    const std::vector<std::unique_ptr<Effect>>& effects() const { return effects_; }
    Eigen::Index parameter_count() const { return static_cast<Eigen::Index>(names_.size()); }
    // Where effect e's real parameters start among the model's (they run to the next effect's start,
    // or to parameter_count()); its k-th real parameter is the one Effect::is_size(k) and the like mean.
    Eigen::Index parameter_offset(std::size_t e) const { return offsets_[e]; }
    // "Rs", "Ld", "Lq", "psi_f", then "<effect>.<parameter>".
    const std::vector<std::string>& parameter_names() const { return names_; }
    // Whether the prediction is linear in effect parameter j (Effect::model_linear_in); false for the
    // base parameters, in which it is affine through the affine split instead.
    bool linear_in(Eigen::Index j) const { return linear_[static_cast<std::size_t>(j)]; }
    // Whether parameter j is an effect's that acts in the sensor stages (before the base parameters):
    // predictions that differ in it start from different inputs.
    bool in_sensor_stages(Eigen::Index j) const { return j >= 4 && sensor_[static_cast<std::size_t>(j - 4)]; }
    // Whether a block's state carries this temperature: only when an effect lists it (model_columns).
    bool reads_temp_winding() const { return reads_temp_winding_; }
    bool reads_temp_magnet() const { return reads_temp_magnet_; }
    // Table 2 for the base parameters, each effect parameter's declared range for the rest (stretched
    // where its plausible range reaches beyond it, Effect::plausible_range): the box a fit searches.
    const Bounds& bounds() const { return bounds_; }
    // The same, each effect parameter's range set to what these data can tell apart from other
    // effects (Effect::plausible_range): what a fitted value is judged against. Not the search box: a
    // fit must be free to land outside it, so that the landing can be reported.
    const Bounds& plausible() const { return plausible_; }
    // The base parameters of `motor` followed by the effects' own values: the parameters a
    // simulation with these effects was made with.
    Eigen::VectorXd parameters_of(const MotorParameters& motor) const;

    Eigen::Index blocks() const { return (data_.size() + block_rows - 1) / block_rows; }
    // First row and row count of block b.
    Eigen::Index block_first(Eigen::Index b) const { return b * block_rows; }
    Eigen::Index block_size(Eigen::Index b) const { return std::min(block_rows, data_.size() - b * block_rows); }

    // A state sized for `rows` rows of these data (allocate once, reuse for every prediction of
    // blocks that size); all rows by default.
    ModelState make_state(Eigen::Index rows = -1) const;
    AffinePrediction make_affine(Eigen::Index rows) const;
    // Predicted logged voltages of rows [first, first + state.size()) into state.u_d, state.u_q.
    void predict(const double* parameters, ModelState& state, Eigen::Index first = 0) const;
    // The same, on the block whose inputs `state` holds from a predict() (or this) at parameters that
    // differ from these in none that is in_sensor_stages: where no later stage changes the inputs
    // (Effect::model_changes_inputs) the block is not loaded again. A Jacobian predicts each block
    // once per column.
    void predict_again(const double* parameters, ModelState& state, Eigen::Index first) const;
    // The offset and base-parameter columns of rows [first, first + out.rows()) at the effect
    // parameters in `parameters` (its base entries are ignored): one run of the sensor stages, one
    // run of the later stages for the offset and one per base parameter in which additive effects
    // are skipped (plus one to remove the constant part of effects whose dependence is not stated).
    void predict_affine(const double* parameters, AffinePrediction& out, Eigen::Index first) const;

    // Scratch for one thread's work on one block: sized for full blocks ([0]) and the last one ([1]).
    struct BlockScratch {
        ModelState state[2];
        AffinePrediction affine[2];
    };
    // This thread's scratch (made on first use, kept for the model's lifetime) and which of its
    // two sizes block b uses.
    BlockScratch& scratch() const { return scratch_.local(); }
    int scratch_index(Eigen::Index b) const { return block_size(b) == block_rows ? 0 : 1; }
    // Predicted logged voltages of all rows into u_d and u_q (each data().size() long), a block at a
    // time, blocks in parallel; the same numbers on any number of threads.
    void predict_rows(const double* parameters, double* u_d, double* u_q) const;

private:
    SteadyStateModel(std::optional<Measurement> owned, const Measurement* view, std::vector<std::unique_ptr<Effect>> effects);
    void load(ModelState& s, Eigen::Index first) const;
    // Rows [first, first + s.size()) of the data are in s.
    void run_stage(ModelStage which, const double* p, ModelState& s, bool base_lane, Eigen::Index first) const;
    // Coefficients onward, from base parameters p[0..3].
    void from_base(const double* p, ModelState& s, bool base_lane, Eigen::Index first) const;
    // Runs effect k at this stage as the logged reference sees it: its voltage over the block's rows
    // through the stated loop (pass_through_current_loop), a run starting at each segment, each gap
    // in the logged time and the block's first row.
    void run_through_loop(std::size_t k, ModelStage which, const double* p, ModelState& s, Eigen::Index first) const;
    // The stated loop's corners R / L from the base model fitted to all rows by least squares.
    void set_loop_corners();

    std::optional<Measurement> owned_;
    const Measurement& data_;
    const Eigen::VectorXd* speed_ = nullptr;  // set_speed
    // The operating scale and the cos and sin of the logged angle, shared with the other models of
    // the same data (hold_shared_tables).
    struct SharedTables;
    std::shared_ptr<const SharedTables> tables_;
    std::vector<std::unique_ptr<Effect>> effects_;
    std::vector<Eigen::Index> offsets_;  // where each effect's parameters start
    std::vector<std::string> names_;
    std::vector<bool> linear_;  // per parameter, see linear_in
    std::vector<bool> sensor_;  // per effect parameter, see in_sensor_stages
    Bounds bounds_, plausible_;
    unsigned stages_ = 0;
    bool affine_effects_ = false;
    bool later_stages_change_inputs_ = false;  // Effect::model_changes_inputs, for predict_affine's lanes
    // Whether an effect runs in the Coefficients or FluxLinkage stage: [0] in a full run, [1] in a base
    // lane (which skips additive effects). from_base takes one pass over the rows where none does.
    bool effects_before_voltage_[2] = {false, false};
    // The stated current loop (alpha 0: none), its corners from the base model's least-squares fit
    // to all rows of the data.
    CurrentLoop loop_;
    double loop_ld_ = 0.0, loop_lq_ = 0.0;  // H: the same fit's inductances, which turn the loop's flux into current
    // Per effect, whether its voltage goes through the stated loop: when the log states the loop and
    // the angle, for an effect that declares the harmonic orders of the angle its voltage has (dead
    // time, flux harmonics; not one that declares none or every order).
    std::vector<bool> through_loop_;
    // Per row, the control periods since the row before, for the stated loop (empty without one).
    std::vector<std::uint8_t> loop_steps_;
    // Temperatures are copied into a block's state only for an effect that lists them
    // (Effect::model_columns): each pass over a long log reads every column it loads from memory.
    bool reads_temp_winding_ = false, reads_temp_magnet_ = false;
    mutable tbb::enumerable_thread_specific<BlockScratch> scratch_;
};

}  // namespace mhb::pmsm

#include "problems/pmsm/model/steady_state_model.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <numbers>
#include <tuple>

#include <Eigen/Cholesky>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/machine/machine.hpp"
#include "problems/pmsm/model/row_kernel.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"

namespace mhb::pmsm {

// What every model of the same data computes from them alike: their operating scale (a pass over the
// rows) and the cos and sin of the logged angle (16 bytes a row). Computed once and shared by the
// models of the same data that exist at the same time, or while a hold_shared_tables handle lives: a
// diagnosis makes tens of models of one log, several at once.
struct SteadyStateModel::SharedTables {
    OperatingScale scale;
    Eigen::ArrayXd cos, sin;

    // The tables of `data` that a model or handle alive now already holds, or new ones. Keyed by the
    // storage of its columns: data must not change or go while a model or handle of them exists, so
    // a live entry is always of the same numbers.
    static std::shared_ptr<const SharedTables> of(const Measurement& data) {
        static std::mutex mutex;
        static std::map<std::tuple<const double*, const double*, Eigen::Index>, std::weak_ptr<const SharedTables>> tables;
        const std::lock_guard lock(mutex);
        std::erase_if(tables, [](const auto& entry) { return entry.second.expired(); });
        auto& slot = tables[{data.i_d.data(), data.theta_e ? data.theta_e->data() : nullptr, data.size()}];
        if (auto table = slot.lock()) return table;
        auto table = std::make_shared<SharedTables>();
        table->scale = operating_scale_of(data);
        if (data.theta_e) {
            table->cos = data.theta_e->array().cos();
            table->sin = data.theta_e->array().sin();
        }
        slot = table;
        return table;
    }
};

std::shared_ptr<const void> SteadyStateModel::hold_shared_tables(const Measurement& data) { return SharedTables::of(data); }

Bounds base_parameter_bounds() {
    Bounds b;
    b.lower = Eigen::Vector4d::Constant(1e-6);
    b.upper = Eigen::Vector4d(100.0, 10.0, 10.0, 10.0);
    return b;
}

OperatingScale operating_scale_of(const Measurement& data) {
    OperatingScale scale;
    if (data.size() == 0) return scale;
    const double current = std::sqrt((data.i_d.array().square() + data.i_q.array().square()).maxCoeff());
    if (current > 0.0) scale.current = current;
    // The flux from the voltage where the speed is at least a tenth of its largest: below that the
    // resistive drop dominates u / omega.
    const double fast = 0.1 * data.omega_e.cwiseAbs().maxCoeff();
    double flux_squared = 0.0;
    for (Eigen::Index k = 0; k < data.size(); ++k) {
        const double w = data.omega_e[k];
        if (fast > 0.0 && std::abs(w) >= fast) flux_squared = std::max(flux_squared, (data.u_d[k] * data.u_d[k] + data.u_q[k] * data.u_q[k]) / (w * w));
    }
    if (flux_squared > 0.0) scale.flux = std::sqrt(flux_squared);
    return scale;
}

SteadyStateModel::SteadyStateModel(const Measurement& data, std::vector<std::unique_ptr<Effect>> effects)
    : SteadyStateModel(std::nullopt, &data, std::move(effects)) {}

SteadyStateModel::SteadyStateModel(Measurement&& data, std::vector<std::unique_ptr<Effect>> effects)
    : SteadyStateModel(std::optional<Measurement>(std::move(data)), nullptr, std::move(effects)) {}

SteadyStateModel::SteadyStateModel(std::optional<Measurement> owned, const Measurement* view,
                                   std::vector<std::unique_ptr<Effect>> effects)
    : owned_(std::move(owned)),
      data_(owned_ ? *owned_ : *view),
      effects_(std::move(effects)),
      names_(base_parameter_names),
      linear_(4, false),
      scratch_([this] {
          BlockScratch b;
          const Eigen::Index tail = data_.size() % block_rows;
          b.state[0] = make_state(std::min(block_rows, data_.size()));
          b.state[1] = make_state(tail);
          b.affine[0] = make_affine(std::min(block_rows, data_.size()));
          b.affine[1] = make_affine(tail);
          return b;
      }) {
    tables_ = SharedTables::of(data_);
    loop_.alpha = 2.0 * std::numbers::pi * data_.current_loop_bandwidth;
    loop_.period = current_loop_period(data_);
    bool any_through_loop = false;
    for (const auto& e : effects_) {
        const std::vector<int> orders = e->angle_orders();
        const bool declared = !orders.empty() && orders != Effect::every_angle_order();
        through_loop_.push_back(loop_.alpha > 0.0 && loop_.period > 0.0 && data_.theta_e && declared);
        any_through_loop = any_through_loop || through_loop_.back();
    }
    if (any_through_loop) {
        // Rows follow each other by whole control periods within a segment; a log without time is
        // taken as one row a period (model_rows gives a subset the time of its rows).
        constexpr int longest_gap = 64;
        loop_steps_.assign(static_cast<std::size_t>(data_.size()), 0);
        for (Eigen::Index k = 1; k < data_.size(); ++k) {
            if (data_.has_segments() && data_.segment[k] != data_.segment[k - 1]) continue;
            if (!data_.t) {
                loop_steps_[static_cast<std::size_t>(k)] = 1;
                continue;
            }
            const double periods = ((*data_.t)[k] - (*data_.t)[k - 1]) / loop_.period;
            const double whole = std::round(periods);
            if (whole >= 1.0 && whole <= longest_gap && std::abs(periods - whole) < 0.25)
                loop_steps_[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(whole);
        }
        set_loop_corners();
    }
    const OperatingScale scale = tables_->scale;
    const Bounds base = base_parameter_bounds();
    std::vector<double> lower(base.lower.data(), base.lower.data() + 4), upper(base.upper.data(), base.upper.data() + 4);
    std::vector<double> plausible_lower = lower, plausible_upper = upper;
    for (const auto& e : effects_) {
        require_columns(*e, data_);
        e->set_scale(scale);
        for (const auto& column : e->model_columns()) {
            reads_temp_winding_ = reads_temp_winding_ || column == "temp_winding";
            reads_temp_magnet_ = reads_temp_magnet_ || column == "temp_magnet";
        }
        offsets_.push_back(static_cast<Eigen::Index>(names_.size()));
        const bool sensor = (e->model_stages() & (ModelStage::SensorCurrents | ModelStage::SensorAngle)) != 0;
        std::size_t real = 0;
        for (const auto& spec : e->parameter_specs()) {
            if (spec.type != ParameterType::Real) continue;
            double lo = spec.minimum, hi = spec.maximum;
            e->plausible_range(real, lo, hi);
            plausible_lower.push_back(lo);
            plausible_upper.push_back(hi);
            linear_.push_back(!sensor && e->model_linear_in(real++));
            sensor_.push_back(sensor);
            names_.push_back(e->name() + "." + spec.name);
            // A plausible end beyond the declared range stretches the search to twice that width.
            lower.push_back(lo < spec.minimum ? spec.maximum - 2.0 * (spec.maximum - lo) : spec.minimum);
            upper.push_back(hi > spec.maximum ? spec.minimum + 2.0 * (hi - spec.minimum) : spec.maximum);
        }
        stages_ |= e->model_stages();
        for (unsigned bit = static_cast<unsigned>(ModelStage::Coefficients); bit <= static_cast<unsigned>(ModelStage::CurrentRipple); bit <<= 1)
            if ((e->model_stages() & bit) != 0) {
                const auto dependence = e->model_base_dependence(static_cast<ModelStage>(bit));
                if (dependence == BaseDependence::Affine) affine_effects_ = true;
                if (e->model_changes_inputs(static_cast<ModelStage>(bit))) later_stages_change_inputs_ = true;
                if (bit == static_cast<unsigned>(ModelStage::Coefficients) || bit == static_cast<unsigned>(ModelStage::FluxLinkage)) {
                    effects_before_voltage_[0] = true;
                    if (dependence != BaseDependence::Additive) effects_before_voltage_[1] = true;
                }
            }
    }
    bounds_.lower = Eigen::Map<Eigen::VectorXd>(lower.data(), static_cast<Eigen::Index>(lower.size()));
    bounds_.upper = Eigen::Map<Eigen::VectorXd>(upper.data(), static_cast<Eigen::Index>(upper.size()));
    plausible_.lower = Eigen::Map<Eigen::VectorXd>(plausible_lower.data(), static_cast<Eigen::Index>(plausible_lower.size()));
    plausible_.upper = Eigen::Map<Eigen::VectorXd>(plausible_upper.data(), static_cast<Eigen::Index>(plausible_upper.size()));
}

Eigen::VectorXd SteadyStateModel::parameters_of(const MotorParameters& motor) const {
    Eigen::VectorXd p(parameter_count());
    p.head<4>() << motor.rs, motor.ld, motor.lq, motor.psi_f;
    for (std::size_t k = 0; k < effects_.size(); ++k)
        p.segment(offsets_[k], effects_[k]->values().size()) = effects_[k]->values();
    return p;
}

ModelState SteadyStateModel::make_state(Eigen::Index rows) const {
    const Eigen::Index n = rows < 0 ? data_.size() : rows;
    ModelState s;
    s.resize(n);
    if (data_.theta_e)
        for (auto* a : {&s.theta, &s.cos_theta, &s.sin_theta}) a->resize(n);
    if (reads_temp_winding_) s.temp_winding.resize(n);
    if (reads_temp_magnet_) s.temp_magnet.resize(n);
    return s;
}

AffinePrediction SteadyStateModel::make_affine(Eigen::Index rows) const {
    AffinePrediction a;
    a.inputs = make_state(rows);
    if (later_stages_change_inputs_) a.lane = make_state(rows);
    for (auto* v : {&a.offset_d, &a.offset_q, &a.residual_d, &a.residual_q}) v->resize(rows);
    for (auto* v : {&a.phi_d, &a.phi_q}) v->resize(rows, 4);
    a.parameters.resize(parameter_count());
    return a;
}

void SteadyStateModel::load(ModelState& s, Eigen::Index first) const {
    const Eigen::Index n = s.size();
    s.i_d = data_.i_d.segment(first, n).array();
    s.i_q = data_.i_q.segment(first, n).array();
    s.omega = (speed_ ? *speed_ : data_.omega_e).segment(first, n).array();
    if (data_.theta_e) {
        s.theta = data_.theta_e->segment(first, n).array();
        s.cos_theta = tables_->cos.segment(first, n);
        s.sin_theta = tables_->sin.segment(first, n);
    }
    if (reads_temp_winding_) s.temp_winding = data_.temp_winding->segment(first, n).array();
    if (reads_temp_magnet_) s.temp_magnet = data_.temp_magnet->segment(first, n).array();
}

LoopPeriod loop_period(const CurrentLoop& loop, double omega) {
    const double cd = loop.integral_corner_d(), cq = loop.integral_corner_q(), t = loop.period;
    // A = m I + B, m = -(c_d + c_q) / 2, B = [[g, omega], [-omega, -g]], g = (c_q - c_d) / 2, B^2 = (g^2 - omega^2) I:
    // e^{A t} = e^{m t} (C I + S B), C and S the cos and sin (or cosh and sinh) of the root.
    const double m = -0.5 * (cd + cq), g = 0.5 * (cq - cd), square = g * g - omega * omega, z = square * t * t;
    double c = 0.0, sn = 0.0;
    if (std::abs(z) < 1e-4) {
        c = 1.0 + z / 2.0 + z * z / 24.0;
        sn = t * (1.0 + z / 6.0 + z * z / 120.0);
    } else if (square < 0.0) {
        const double root = std::sqrt(-square);
        c = std::cos(root * t);
        sn = std::sin(root * t) / root;
    } else {
        const double root = std::sqrt(square);
        c = std::cosh(root * t);
        sn = std::sinh(root * t) / root;
    }
    const double decay = std::exp(m * t);
    LoopPeriod p{};
    p.phi[0][0] = decay * (c + sn * g);
    p.phi[0][1] = decay * sn * omega;
    p.phi[1][0] = -decay * sn * omega;
    p.phi[1][1] = decay * (c - sn * g);
    // gamma = A^{-1} (e^{A t} - I), or its series where A t is small (no resistance, no speed).
    const double a00 = -cd, a01 = omega, a10 = -omega, a11 = -cq;
    const double size = std::max({std::abs(cd), std::abs(cq), std::abs(omega)}) * t;
    if (size < 1e-6) {
        const double h = 0.5 * t * t;
        p.gamma[0][0] = t + h * a00;
        p.gamma[0][1] = h * a01;
        p.gamma[1][0] = h * a10;
        p.gamma[1][1] = t + h * a11;
    } else {
        const double det = a00 * a11 - a01 * a10;
        const double i00 = a11 / det, i01 = -a01 / det, i10 = -a10 / det, i11 = a00 / det;
        const double e00 = p.phi[0][0] - 1.0, e01 = p.phi[0][1], e10 = p.phi[1][0], e11 = p.phi[1][1] - 1.0;
        p.gamma[0][0] = i00 * e00 + i01 * e10;
        p.gamma[0][1] = i00 * e01 + i01 * e11;
        p.gamma[1][0] = i10 * e00 + i11 * e10;
        p.gamma[1][1] = i10 * e01 + i11 * e11;
    }
    return p;
}

void pass_through_current_loop(const CurrentLoop& loop, const LoopPeriod& p, const double* omega, const std::uint8_t* steps, double* w_d,
                               double* w_q, Eigen::Index n, double* left_d, double* left_q) {
    // x: the flux L i of the current the loop leaves (rotor frame, d and q), at the row's sample; y:
    // the PI's integral, a voltage. The machine: dx_d/dt = applied_d - law_d + omega x_q - c_d x_d,
    // dx_q/dt = applied_q - law_q - omega x_d - c_q x_q (c: the corners R / L), over a period
    // loop_period. The controller at a sample: -alpha x + y less the feed-forward's j omega x (d:
    // -omega x_q, q: +omega x_d), then y -= alpha c T x. The model's rows hold R i + j omega L i of
    // the current, so what it lacks of the reference is -alpha x + y - c x.
    const bool integral = loop.integral();
    const double alpha = loop.alpha, period = loop.period, cd = loop.integral_corner_d(), cq = loop.integral_corner_q();
    double xd = 0.0, xq = 0.0, yd = 0.0, yq = 0.0, applied_d = 0.0, applied_q = 0.0, computed_d = 0.0, computed_q = 0.0;
    double before_d = 0.0, before_q = 0.0, out_d = 0.0, out_q = 0.0;
    for (Eigen::Index r = 0; r < n; ++r) {
        const double law_d = w_d[r], law_q = w_q[r];
        if (r == 0 || steps[r] == 0) {
            // The steady state under a constant law: with the integral the current is back on its
            // reference and the integral holds the law; without it the proportional part does.
            if (integral) {
                xd = xq = 0.0;  // (then -alpha x + y - c x is the law)
                yd = law_d;
                yq = law_q;
            } else {
                xd = -law_d / alpha;
                xq = -law_q / alpha;
                yd = yq = 0.0;
            }
            computed_d = applied_d = -alpha * xd + yd - omega[r] * xq;
            computed_q = applied_q = -alpha * xq + yq + omega[r] * xd;
            out_d = law_d;
            out_q = law_q;
        } else {
            const double w = omega[r - 1];
            const double count = steps[r];
            for (int k = 0; k < steps[r]; ++k) {
                // The law over the period: its mean on the line between the rows' values (the loss
                // follows the current through the period, not its value at the period's start).
                const double f = (k + 0.5) / count;
                const double bd = applied_d - (before_d + (law_d - before_d) * f), bq = applied_q - (before_q + (law_q - before_q) * f);
                const double nd = p.phi[0][0] * xd + p.phi[0][1] * xq + p.gamma[0][0] * bd + p.gamma[0][1] * bq;
                const double nq = p.phi[1][0] * xd + p.phi[1][1] * xq + p.gamma[1][0] * bd + p.gamma[1][1] * bq;
                xd = nd;
                xq = nq;
                applied_d = computed_d;
                applied_q = computed_q;
                computed_d = -alpha * xd + yd - w * xq;
                computed_q = -alpha * xq + yq + w * xd;
                out_d = -alpha * xd + yd - cd * xd;
                out_q = -alpha * xq + yq - cq * xq;
                if (integral) {
                    yd -= alpha * cd * period * xd;
                    yq -= alpha * cq * period * xq;
                }
            }
        }
        before_d = law_d;
        before_q = law_q;
        w_d[r] = out_d;
        w_q[r] = out_q;
        if (left_d != nullptr) {
            left_d[r] = xd;
            left_q[r] = xq;
        }
    }
}

void SteadyStateModel::set_loop_corners() {
    // The base model is linear in Rs, Ld, Lq, psi_f: u_d = Rs i_d - omega Lq i_q, u_q = Rs i_q +
    // omega Ld i_d + omega psi_f. Fitted alone it reads an inverter's voltage error, which does not
    // grow with the current, as resistance (on the 5 kW machine with 1.5 us of dead time, 2.8 times
    // R_s), so a fifth column takes that error's shape, the phase currents' signs turned into the
    // rotor frame (the loop needs the angle; the column is linear, so the fit stays exact). Normal
    // equations over all rows, scaled so that columns of very different size do not decide.
    using Vector5d = Eigen::Matrix<double, 5, 1>;
    using Matrix5d = Eigen::Matrix<double, 5, 5>;
    Matrix5d gram = Matrix5d::Zero();
    Vector5d moment = Vector5d::Zero();
    for (Eigen::Index k = 0; k < data_.size(); ++k) {
        const double id = data_.i_d[k], iq = data_.i_q[k], w = data_.omega_e[k];
        const Complex turn(tables_->cos[k], tables_->sin[k]);  // the table's angle, as park and inverse_park turn
        const auto phase = inverse_clarke(Complex(id, iq) * turn);
        const Complex sign = clarke(std::copysign(1.0, phase[0]), std::copysign(1.0, phase[1]), std::copysign(1.0, phase[2])) * std::conj(turn);
        Vector5d row_d, row_q;
        row_d << id, 0.0, -w * iq, 0.0, sign.real();
        row_q << iq, w * id, 0.0, w, sign.imag();
        gram.noalias() += row_d * row_d.transpose() + row_q * row_q.transpose();
        moment.noalias() += row_d * data_.u_d[k] + row_q * data_.u_q[k];
    }
    const Vector5d scale = gram.diagonal().cwiseSqrt().cwiseMax(1e-300).cwiseInverse();
    const Matrix5d scaled = scale.asDiagonal() * gram * scale.asDiagonal();
    const Vector5d base = scale.asDiagonal() * scaled.ldlt().solve(scale.asDiagonal() * moment);
    // A log that does not determine them (no current, no speed) leaves the corners at zero: the
    // proportional loop.
    if (base.allFinite() && base[0] > 0.0 && base[1] > 0.0 && base[2] > 0.0) {
        loop_.corner_d = base[0] / base[1];
        loop_.corner_q = base[0] / base[2];
        loop_ld_ = base[1];
        loop_lq_ = base[2];
    }
}

void SteadyStateModel::run_through_loop(std::size_t effect, ModelStage which, const double* p, ModelState& s, Eigen::Index first) const {
    const Effect& e = *effects_[effect];
    const Eigen::Index n = s.size();
    // Per block size a thread meets (a log's blocks and its tail): the state the law is taken at
    // for the loop.
    struct LoopLaw {
        ModelState state;
        Eigen::ArrayXd mean_i_d, mean_i_q, mean_psi_d, mean_psi_q, left_d, left_q, law_d, law_q;
    };
    thread_local std::vector<LoopLaw> laws;
    auto found = std::find_if(laws.begin(), laws.end(), [&](const LoopLaw& l) { return l.law_d.size() == n; });
    LoopLaw& l = found != laws.end() ? *found : laws.emplace_back();
    if (l.law_d.size() != n) {
        l.state.resize(n);
        for (auto* a : {&l.mean_i_d, &l.mean_i_q, &l.mean_psi_d, &l.mean_psi_q, &l.left_d, &l.left_q, &l.law_d, &l.law_q})
            a->resize(n);
    }
    // Each row keeps the law's own value at its measured state; the loop adds what it makes of the law
    // beyond that.
    e.model(which, p, s);
    // Runs of one operating point (a segment within the block, which starts a run of the loop), each
    // with its period map at the run's mean speed (the speed's noise turns the frame by microradians
    // a period).
    thread_local std::vector<LoopPeriod> periods;
    thread_local std::vector<Eigen::Index> run_ends;
    periods.clear();
    run_ends.clear();
    for (Eigen::Index begin = 0; begin < n;) {
        Eigen::Index end = begin + 1;
        if (data_.has_segments())
            while (end < n && data_.segment[first + end] == data_.segment[first + begin]) ++end;
        else
            end = n;
        periods.push_back(loop_period(loop_, s.omega.segment(begin, end - begin).mean()));
        run_ends.push_back(end);
        begin = end;
    }
    // What the loop makes of the law is taken at the current less its sensors' noise: the run's mean
    // state plus the ripple the loop itself leaves (x / L, found by a first pass at the mean state).
    // At each row's measured current a law that follows the current (a dead-time band wide enough to
    // be a resistance) would copy the sensors' noise into the loop, whose answer to it is delay's
    // signature; at the mean state alone the zero crossings sit where the ripple does not move them
    // (docs/diagnosis.md, section 8).
    ModelState& g = l.state;
    g.theta = s.theta;
    g.cos_theta = s.cos_theta;
    g.sin_theta = s.sin_theta;
    g.ld = s.ld;
    g.lq = s.lq;
    g.temp_winding.resize(s.temp_winding.size());
    g.temp_magnet.resize(s.temp_magnet.size());
    const auto for_each_run = [&](auto&& f) {
        Eigen::Index begin = 0;
        for (const Eigen::Index end : run_ends) {
            f(begin, end - begin);
            begin = end;
        }
    };
    for_each_run([&](Eigen::Index begin, Eigen::Index rows) {
        for (auto [to, from] : {std::pair{&g.i_d, &s.i_d}, std::pair{&g.i_q, &s.i_q}, std::pair{&g.omega, &s.omega}, std::pair{&g.rs, &s.rs},
                                std::pair{&g.psi_f, &s.psi_f}, std::pair{&g.psi_d, &s.psi_d}, std::pair{&g.psi_q, &s.psi_q},
                                std::pair{&g.temp_winding, &s.temp_winding}, std::pair{&g.temp_magnet, &s.temp_magnet}})
            if (from->size() > 0) to->segment(begin, rows).setConstant(from->segment(begin, rows).mean());
    });
    const bool ripple = loop_ld_ > 0.0 && loop_lq_ > 0.0;
    if (ripple) {
        l.mean_i_d = g.i_d;
        l.mean_i_q = g.i_q;
        l.mean_psi_d = g.psi_d;
        l.mean_psi_q = g.psi_q;
    }
    // One refinement: the ripple of the law at the mean state. Further passes alternate about the
    // fixed point rather than settle on it (noise-free 5 kW dead time, docs/diagnosis.md, section 8),
    // each at the cost of another run of the loop's rows.
    const int passes = ripple ? 2 : 1;
    for (int pass = 0; pass < passes; ++pass) {
        if (pass == 1) {
            // The ripple: the flux the loop leaves, less its run's mean (a proportional loop's offset
            // is in the measured mean already).
            for_each_run([&](Eigen::Index begin, Eigen::Index rows) {
                l.left_d.segment(begin, rows) -= l.left_d.segment(begin, rows).mean();
                l.left_q.segment(begin, rows) -= l.left_q.segment(begin, rows).mean();
            });
            g.i_d = l.mean_i_d + l.left_d / loop_ld_;
            g.i_q = l.mean_i_q + l.left_q / loop_lq_;
            g.psi_d = l.mean_psi_d + l.left_d;
            g.psi_q = l.mean_psi_q + l.left_q;
        }
        g.u_d.setZero();
        g.u_q.setZero();
        e.model(which, p, g);
        l.law_d = g.u_d;
        l.law_q = g.u_q;
        const bool last = pass + 1 == passes;
        std::size_t run = 0;
        for_each_run([&](Eigen::Index begin, Eigen::Index rows) {
            pass_through_current_loop(loop_, periods[run++], s.omega.data() + begin, loop_steps_.data() + first + begin, g.u_d.data() + begin,
                                      g.u_q.data() + begin, rows, last ? nullptr : l.left_d.data() + begin,
                                      last ? nullptr : l.left_q.data() + begin);
        });
    }
    s.u_d += g.u_d - l.law_d;
    s.u_q += g.u_q - l.law_q;
}

void SteadyStateModel::run_stage(ModelStage which, const double* p, ModelState& s, bool base_lane, Eigen::Index first) const {
    if (!acts_in(stages_, which)) return;
    for (std::size_t k = 0; k < effects_.size(); ++k) {
        const Effect& e = *effects_[k];
        if (!acts_in(e.model_stages(), which)) continue;
        if (base_lane && e.model_base_dependence(which) == BaseDependence::Additive) continue;
        if (through_loop_[k] && (which == ModelStage::MachineVoltage || which == ModelStage::InverterError))
            run_through_loop(k, which, p + offsets_[k], s, first);
        else e.model(which, p + offsets_[k], s);
    }
}

namespace {

// from_base's stages without effects between them, over n rows (distinct arrays, said so that the loop
// vectorises).
MHB_ROW_KERNEL void base_voltage(const double* p, Eigen::Index n, const double* __restrict i_d, const double* __restrict i_q,
                                 const double* __restrict omega, double* __restrict rs_out, double* __restrict psi_f_out,
                                 double* __restrict psi_d_out, double* __restrict psi_q_out, double* __restrict u_d,
                                 double* __restrict u_q) {
    const double rs = p[0], ld = p[1], lq = p[2], psi_f = p[3];
    for (Eigen::Index k = 0; k < n; ++k) {
        rs_out[k] = rs;
        psi_f_out[k] = psi_f;
        const double psi_d = ld * i_d[k] + psi_f, psi_q = lq * i_q[k];
        psi_d_out[k] = psi_d;
        psi_q_out[k] = psi_q;
        u_d[k] = rs * i_d[k] - omega[k] * psi_q;
        u_q[k] = rs * i_q[k] + omega[k] * psi_d;
    }
}

// The same stages one at a time, where effects run between them.
MHB_ROW_KERNEL void linear_fluxes(double ld, double lq, Eigen::Index n, const double* __restrict i_d, const double* __restrict i_q,
                                  const double* __restrict psi_f, double* __restrict psi_d, double* __restrict psi_q) {
    for (Eigen::Index k = 0; k < n; ++k) {
        psi_d[k] = ld * i_d[k] + psi_f[k];
        psi_q[k] = lq * i_q[k];
    }
}
MHB_ROW_KERNEL void machine_voltage(Eigen::Index n, const double* __restrict rs, const double* __restrict i_d, const double* __restrict i_q,
                                    const double* __restrict omega, const double* __restrict psi_d, const double* __restrict psi_q,
                                    double* __restrict u_d, double* __restrict u_q) {
    for (Eigen::Index k = 0; k < n; ++k) {
        u_d[k] = rs[k] * i_d[k] - omega[k] * psi_q[k];
        u_q[k] = rs[k] * i_q[k] + omega[k] * psi_d[k];
    }
}

}  // namespace

void SteadyStateModel::from_base(const double* p, ModelState& s, bool base_lane, Eigen::Index first) const {
    s.ld = p[1];
    s.lq = p[2];
    if (!effects_before_voltage_[base_lane ? 1 : 0]) {
        // No effect runs between them (a base lane skips additive ones): the coefficients, the fluxes
        // and the voltage in one pass over the rows rather than six (the same operations, so the same
        // numbers).
        base_voltage(p, s.size(), s.i_d.data(), s.i_q.data(), s.omega.data(), s.rs.data(), s.psi_f.data(), s.psi_d.data(), s.psi_q.data(),
                     s.u_d.data(), s.u_q.data());
    } else {
        s.rs.setConstant(p[0]);
        s.psi_f.setConstant(p[3]);
        run_stage(ModelStage::Coefficients, p, s, base_lane, first);
        linear_fluxes(p[1], p[2], s.size(), s.i_d.data(), s.i_q.data(), s.psi_f.data(), s.psi_d.data(), s.psi_q.data());
        run_stage(ModelStage::FluxLinkage, p, s, base_lane, first);
        machine_voltage(s.size(), s.rs.data(), s.i_d.data(), s.i_q.data(), s.omega.data(), s.psi_d.data(), s.psi_q.data(), s.u_d.data(),
                        s.u_q.data());
    }
    for (auto stage : {ModelStage::MachineVoltage, ModelStage::CurrentRipple, ModelStage::InverterError, ModelStage::ControllerFrame,
                       ModelStage::Delay, ModelStage::LoggedVoltage})
        run_stage(stage, p, s, base_lane, first);
}

void SteadyStateModel::predict(const double* p, ModelState& s, Eigen::Index first) const {
    load(s, first);
    run_stage(ModelStage::SensorCurrents, p, s, false, first);
    run_stage(ModelStage::SensorAngle, p, s, false, first);
    from_base(p, s, false, first);
}

void SteadyStateModel::predict_again(const double* p, ModelState& s, Eigen::Index first) const {
    if (later_stages_change_inputs_) {
        predict(p, s, first);
        return;
    }
    from_base(p, s, false, first);
}

void SteadyStateModel::predict_rows(const double* p, double* u_d, double* u_q) const {
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, blocks()), [&](const tbb::blocked_range<Eigen::Index>& range) {
        BlockScratch& scratch = this->scratch();
        for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
            ModelState& s = scratch.state[scratch_index(b)];
            const Eigen::Index first = block_first(b);
            predict(p, s, first);
            Eigen::Map<Eigen::ArrayXd>(u_d + first, s.size()) = s.u_d;
            Eigen::Map<Eigen::ArrayXd>(u_q + first, s.size()) = s.u_q;
        }
    });
}

void SteadyStateModel::predict_affine(const double* p, AffinePrediction& out, Eigen::Index first) const {
    ModelState& in = out.inputs;
    load(in, first);
    run_stage(ModelStage::SensorCurrents, p, in, false, first);
    run_stage(ModelStage::SensorAngle, p, in, false, first);
    // Where a later stage may change the currents, the angle or the like, each run starts from a copy
    // of the inputs; otherwise the runs share them (the runs overwrite only what from_base sets).
    auto restart = [&](ModelState& s) {
        if (!later_stages_change_inputs_) return;
        s.i_d = in.i_d;
        s.i_q = in.i_q;
        s.omega = in.omega;
        s.theta = in.theta;
        s.cos_theta = in.cos_theta;
        s.sin_theta = in.sin_theta;
        s.temp_winding = in.temp_winding;
        s.temp_magnet = in.temp_magnet;
    };
    Eigen::VectorXd& q = out.parameters;
    q = Eigen::Map<const Eigen::VectorXd>(p, parameter_count());
    ModelState& s = later_stages_change_inputs_ ? out.lane : in;
    q.head<4>().setZero();
    restart(s);
    from_base(q.data(), s, false, first);
    out.offset_d = s.u_d;
    out.offset_q = s.u_q;
    for (int j = 0; j < 4; ++j) {
        q.head<4>().setZero();
        q[j] = 1.0;
        restart(s);
        from_base(q.data(), s, true, first);
        out.phi_d.col(j) = s.u_d;
        out.phi_q.col(j) = s.u_q;
    }
    if (!affine_effects_) return;
    q.head<4>().setZero();
    restart(s);
    from_base(q.data(), s, true, first);
    for (int j = 0; j < 4; ++j) {
        out.phi_d.col(j) -= s.u_d;
        out.phi_q.col(j) -= s.u_q;
    }
}

void require_columns(const Effect& effect, const Measurement& data) {
    for (const auto& column : effect.model_columns()) {
        const bool present = column == "theta_e"        ? data.theta_e.has_value()
                             : column == "temp_winding" ? data.temp_winding.has_value()
                             : column == "temp_magnet"  ? data.temp_magnet.has_value()
                             : column == "t"            ? data.t.has_value()
                                                        : true;
        if (!present)
            throw InputError(data.source, 0, column,
                             fmt::format("the {} effect needs this column, which the data lack", effect.name()));
    }
}

}  // namespace mhb::pmsm

#include "problems/pmsm/model/steady_state_model.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <mutex>
#include <numbers>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <fmt/format.h>

#include "framework/input_error.hpp"

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
    loop_alpha_ = 2.0 * std::numbers::pi * data_.current_loop_bandwidth;
    for (const auto& e : effects_) {
        std::vector<int> orders = e->angle_orders();
        std::sort(orders.begin(), orders.end());
        // Successive products reach every order only when each is a multiple of the first.
        const bool declared = !orders.empty() && orders != Effect::every_angle_order() && orders.front() > 0 &&
                              std::all_of(orders.begin(), orders.end(), [&](int m) { return m % orders.front() == 0; });
        loop_orders_.push_back(loop_alpha_ > 0.0 && data_.theta_e && declared ? std::move(orders) : std::vector<int>{});
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
            names_.push_back(e->name() + "." + spec.name);
            // A plausible end beyond the declared range stretches the search to twice that width.
            lower.push_back(lo < spec.minimum ? spec.maximum - 2.0 * (spec.maximum - lo) : spec.minimum);
            upper.push_back(hi > spec.maximum ? spec.minimum + 2.0 * (hi - spec.minimum) : spec.maximum);
        }
        stages_ |= e->model_stages();
        for (unsigned bit = static_cast<unsigned>(ModelStage::Coefficients); bit <= static_cast<unsigned>(ModelStage::CurrentRipple); bit <<= 1)
            if ((e->model_stages() & bit) != 0 && e->model_base_dependence(static_cast<ModelStage>(bit)) == BaseDependence::Affine)
                affine_effects_ = true;
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
    a.lane = make_state(rows);
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

std::complex<double> loop_response(double alpha, double delay, double omega, double omega_h) {
    using namespace std::complex_literals;
    const std::complex<double> a = alpha - 1i * omega;
    return alpha / (a * std::exp(-1i * omega_h * delay) + 1i * (omega_h + omega));
}

void SteadyStateModel::run_through_loop(std::size_t effect, ModelStage which, const double* p, ModelState& s, Eigen::Index first) const {
    const Effect& e = *effects_[effect];
    // Each row takes its own value of the law; what the loop changes, the law's harmonics, is taken at
    // the mean state of the row's operating point within the block (a run of one segment), so that
    // the noise of the row's current does not enter it.
    struct Grid {
        std::vector<int> declared;         // the effect's orders (loop_orders_)
        std::vector<int> orders;           // m = +order and -order for each of them
        ModelState state;                  // a turn of the angle at an operating point's mean state
        Eigen::ArrayXcd turns;             // e^{-j m theta_k}, points x orders, column-major
        Eigen::ArrayXcd change;            // (G - 1) times the law's coefficient of each m
    };
    // One grid per set of orders a thread meets (dead time's, a flux harmonic's), made once.
    thread_local std::vector<Grid> grids;
    const std::vector<int>& declared = loop_orders_[effect];
    auto found = std::find_if(grids.begin(), grids.end(), [&](const Grid& g) { return g.declared == declared; });
    const bool known = found != grids.end();
    Grid& grid = known ? *found : grids.emplace_back();
    const Eigen::Index points = 2 * declared.back() + 8;
    ModelState& g = grid.state;
    if (!known) {
        grid.declared = declared;
        for (const int order : declared) grid.orders.insert(grid.orders.end(), {order, -order});
    }
    const std::vector<int>& orders = grid.orders;
    const auto count = static_cast<Eigen::Index>(orders.size());
    if (!known) {
        g.resize(points);
        g.theta.resize(points);
        g.cos_theta.resize(points);
        g.sin_theta.resize(points);
        grid.turns.resize(points * count);
        for (Eigen::Index k = 0; k < points; ++k) {
            g.theta[k] = 2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(points);
            g.cos_theta[k] = std::cos(g.theta[k]);
            g.sin_theta[k] = std::sin(g.theta[k]);
            for (Eigen::Index j = 0; j < count; ++j)
                grid.turns[j * points + k] = std::polar(1.0, -static_cast<double>(orders[static_cast<std::size_t>(j)]) * g.theta[k]);
        }
        grid.change.resize(count);
    }
    e.model(which, p, s);
    g.ld = s.ld;
    g.lq = s.lq;
    const Eigen::Index n = s.size();
    for (Eigen::Index begin = 0; begin < n;) {
        Eigen::Index end = begin + 1;
        if (data_.has_segments())
            while (end < n && data_.segment[first + end] == data_.segment[first + begin]) ++end;
        else
            end = n;
        const Eigen::Index rows = end - begin;
        auto mean = [&](const Eigen::ArrayXd& a) { return a.segment(begin, rows).mean(); };
        const double omega = mean(s.omega);
        g.i_d.setConstant(mean(s.i_d));
        g.i_q.setConstant(mean(s.i_q));
        g.omega.setConstant(omega);
        g.rs.setConstant(mean(s.rs));
        g.psi_f.setConstant(mean(s.psi_f));
        g.psi_d.setConstant(mean(s.psi_d));
        g.psi_q.setConstant(mean(s.psi_q));
        if (s.temp_winding.size() > 0) g.temp_winding.setConstant(points, mean(s.temp_winding));
        else g.temp_winding.resize(0);
        if (s.temp_magnet.size() > 0) g.temp_magnet.setConstant(points, mean(s.temp_magnet));
        else g.temp_magnet.resize(0);
        g.u_d.setZero();
        g.u_q.setZero();
        e.model(which, p, g);
        // Each harmonic m of the law's voltage at that state, times the loop's response less one:
        // what the steady law says and the logged reference does not hold.
        for (Eigen::Index j = 0; j < count; ++j) {
            std::complex<double> c = 0.0;
            for (Eigen::Index k = 0; k < points; ++k) c += std::complex<double>(g.u_d[k], g.u_q[k]) * grid.turns[j * points + k];
            const double m = static_cast<double>(orders[static_cast<std::size_t>(j)]);
            grid.change[j] = (loop_response(loop_alpha_, data_.current_loop_delay, omega, m * omega) - 1.0) * c / static_cast<double>(points);
        }
        // The orders are multiples of the first (ascending, loop_orders_): e^{j m theta} by successive
        // products of e^{j step theta} rather than a power per order and row.
        const int step = declared.front();
        for (Eigen::Index r = begin; r < end; ++r) {
            const std::complex<double> base = std::pow(std::complex<double>(s.cos_theta[r], s.sin_theta[r]), step);
            std::complex<double> turn = 1.0, v = 0.0;
            int at = 0;
            for (Eigen::Index j = 0; j < count; j += 2) {
                // e^{j m theta} and its conjugate for the pair +m, -m.
                for (const int m = orders[static_cast<std::size_t>(j)]; at < m; at += step) turn *= base;
                v += grid.change[j] * turn + grid.change[j + 1] * std::conj(turn);
            }
            s.u_d[r] += v.real();
            s.u_q[r] += v.imag();
        }
        begin = end;
    }
}

void SteadyStateModel::run_stage(ModelStage which, const double* p, ModelState& s, bool base_lane, Eigen::Index first) const {
    if (!acts_in(stages_, which)) return;
    for (std::size_t k = 0; k < effects_.size(); ++k) {
        const Effect& e = *effects_[k];
        if (!acts_in(e.model_stages(), which)) continue;
        if (base_lane && e.model_base_dependence(which) == BaseDependence::Additive) continue;
        if (!loop_orders_[k].empty() && (which == ModelStage::MachineVoltage || which == ModelStage::InverterError))
            run_through_loop(k, which, p + offsets_[k], s, first);
        else e.model(which, p + offsets_[k], s);
    }
}

void SteadyStateModel::from_base(const double* p, ModelState& s, bool base_lane, Eigen::Index first) const {
    s.rs.setConstant(p[0]);
    s.psi_f.setConstant(p[3]);
    run_stage(ModelStage::Coefficients, p, s, base_lane, first);
    s.ld = p[1];
    s.lq = p[2];
    s.psi_d = p[1] * s.i_d + s.psi_f;
    s.psi_q = p[2] * s.i_q;
    run_stage(ModelStage::FluxLinkage, p, s, base_lane, first);
    s.u_d = s.rs * s.i_d - s.omega * s.psi_q;
    s.u_q = s.rs * s.i_q + s.omega * s.psi_d;
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
    // Later stages may change the currents and the angle too, so each run starts from the inputs.
    auto restart = [&](ModelState& s) {
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
    ModelState& s = out.lane;
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

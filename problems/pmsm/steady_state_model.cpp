#include "problems/pmsm/steady_state_model.hpp"

namespace mhb::pmsm {

Bounds base_parameter_bounds() {
    Bounds b;
    b.lower = Eigen::Vector4d::Constant(1e-6);
    b.upper = Eigen::Vector4d(100.0, 10.0, 10.0, 10.0);
    return b;
}

SteadyStateModel::SteadyStateModel(Measurement data, std::vector<std::unique_ptr<Effect>> effects)
    : data_(std::move(data)), effects_(std::move(effects)), names_(base_parameter_names) {
    if (data_.theta_e) {
        cos_theta_ = data_.theta_e->array().cos();
        sin_theta_ = data_.theta_e->array().sin();
    }
    const Bounds base = base_parameter_bounds();
    std::vector<double> lower(base.lower.data(), base.lower.data() + 4), upper(base.upper.data(), base.upper.data() + 4);
    for (const auto& e : effects_) {
        require_columns(*e, data_);
        offsets_.push_back(static_cast<Eigen::Index>(names_.size()));
        for (const auto& spec : e->parameter_specs()) {
            if (spec.type != ParameterType::Real) continue;
            names_.push_back(e->name() + "." + spec.name);
            lower.push_back(spec.minimum);
            upper.push_back(spec.maximum);
        }
        stages_ |= e->model_stages();
    }
    bounds_.lower = Eigen::Map<Eigen::VectorXd>(lower.data(), static_cast<Eigen::Index>(lower.size()));
    bounds_.upper = Eigen::Map<Eigen::VectorXd>(upper.data(), static_cast<Eigen::Index>(upper.size()));
}

Eigen::VectorXd SteadyStateModel::parameters_of(const MotorParameters& motor) const {
    Eigen::VectorXd p(parameter_count());
    p.head<4>() << motor.rs, motor.ld, motor.lq, motor.psi_f;
    for (std::size_t k = 0; k < effects_.size(); ++k)
        p.segment(offsets_[k], effects_[k]->values().size()) = effects_[k]->values();
    return p;
}

ModelState SteadyStateModel::make_state() const {
    ModelState s;
    s.data = &data_;
    s.resize(data_.size());
    return s;
}

void SteadyStateModel::predict(const double* p, ModelState& s) const {
    auto stage = [&](ModelStage which) {
        if (!acts_in(stages_, which)) return;
        for (std::size_t k = 0; k < effects_.size(); ++k)
            if (acts_in(effects_[k]->model_stages(), which)) effects_[k]->model(which, p + offsets_[k], s);
    };
    s.data = &data_;
    s.i_d = data_.i_d.array();
    s.i_q = data_.i_q.array();
    s.omega = data_.omega_e.array();
    if (data_.theta_e) {
        s.theta = data_.theta_e->array();
        s.cos_theta = cos_theta_;
        s.sin_theta = sin_theta_;
    }
    stage(ModelStage::SensorCurrents);
    stage(ModelStage::SensorAngle);
    s.rs.setConstant(p[0]);
    s.psi_f.setConstant(p[3]);
    stage(ModelStage::Coefficients);
    s.psi_d = p[1] * s.i_d + s.psi_f;
    s.psi_q = p[2] * s.i_q;
    stage(ModelStage::FluxLinkage);
    s.u_d = s.rs * s.i_d - s.omega * s.psi_q;
    s.u_q = s.rs * s.i_q + s.omega * s.psi_d;
    stage(ModelStage::MachineVoltage);
    stage(ModelStage::InverterError);
    stage(ModelStage::ControllerFrame);
    stage(ModelStage::Delay);
    stage(ModelStage::LoggedVoltage);
}

}  // namespace mhb::pmsm

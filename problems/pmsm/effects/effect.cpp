#include "problems/pmsm/effects/effect.hpp"
#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {

namespace {
const bool effects_listed = list_registry<EffectFactory>("effects");
}  // namespace

void ModelState::resize(Eigen::Index n) {
    for (auto* a : {&i_d, &i_q, &omega, &rs, &psi_f, &psi_d, &psi_q, &u_d, &u_q}) a->resize(n);
}

void ModelState::rotate_angle(double delta) {
    if (theta.size() == 0) return;
    theta += delta;
    turn_rows(std::cos(delta), std::sin(delta), theta.size(), cos_theta.data(), sin_theta.data());
}

Effect::Effect(std::string name, const ParameterSet& settings) : name_(std::move(name)), settings_(settings) {
    specs_ = EffectRegistry::instance().at(name_, "effect").parameters;
    for (const auto& s : specs_)
        if (s.type == ParameterType::Real) parameter_names_.push_back(s.name);
    values_.resize(static_cast<Eigen::Index>(parameter_names_.size()));
    for (std::size_t k = 0; k < parameter_names_.size(); ++k)
        values_[static_cast<Eigen::Index>(k)] = settings_.real(parameter_names_[k]);
}

std::unique_ptr<Effect> make_effect(const std::string& name, const std::map<std::string, ParameterValue>& values) {
    const auto& entry = EffectRegistry::instance().at(name, "effect");
    return entry.create(ParameterSet(entry.parameters, values));
}

std::vector<int> Effect::every_angle_order() {
    // Beyond any order a lack-of-fit test asks about (diagnosis/lack_of_fit.hpp).
    std::vector<int> out(64);
    for (int k = 0; k < 64; ++k) out[static_cast<std::size_t>(k)] = k + 1;
    return out;
}

}  // namespace mhb::pmsm

#pragma once
// The steady-state voltage model: the base model of seed eq. (2),
//   u_d = R_s i_d - omega L_q i_q,   u_q = R_s i_q + omega L_d i_d + omega psi_f,
// with any chosen effects applied stage by stage (effects/effect.hpp). Parameters are the four base
// parameters followed by each effect's real parameters in declaration order.
#include <memory>
#include <string>
#include <vector>

#include "framework/problem.hpp"
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {

// Table 2 of the seed: the search box of the base parameters Rs, Ld, Lq, psi_f.
Bounds base_parameter_bounds();
inline const std::vector<std::string> base_parameter_names{"Rs", "Ld", "Lq", "psi_f"};

class SteadyStateModel {
public:
    // Throws InputError when an effect needs a column the data lack.
    SteadyStateModel(Measurement data, std::vector<std::unique_ptr<Effect>> effects);
    SteadyStateModel(const SteadyStateModel&) = delete;
    SteadyStateModel& operator=(const SteadyStateModel&) = delete;

    const Measurement& data() const { return data_; }
    const std::vector<std::unique_ptr<Effect>>& effects() const { return effects_; }
    Eigen::Index parameter_count() const { return static_cast<Eigen::Index>(names_.size()); }
    // "Rs", "Ld", "Lq", "psi_f", then "<effect>.<parameter>".
    const std::vector<std::string>& parameter_names() const { return names_; }
    // Table 2 for the base parameters, each effect parameter's plausible range for the rest.
    const Bounds& bounds() const { return bounds_; }
    // The base parameters of `motor` followed by the effects' own values: the parameters a
    // simulation with these effects was made with.
    Eigen::VectorXd parameters_of(const MotorParameters& motor) const;

    // A state sized for the data (allocate once per thread, reuse for every prediction).
    ModelState make_state() const;
    // Predicted logged voltages into state.u_d, state.u_q.
    void predict(const double* parameters, ModelState& state) const;

private:
    Measurement data_;
    Eigen::ArrayXd cos_theta_, sin_theta_;  // of the logged angle, once
    std::vector<std::unique_ptr<Effect>> effects_;
    std::vector<Eigen::Index> offsets_;  // where each effect's parameters start
    std::vector<std::string> names_;
    Bounds bounds_;
    unsigned stages_ = 0;
};

}  // namespace mhb::pmsm

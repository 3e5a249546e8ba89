#pragma once
// jSO (Brest, Maučec & Bošković, CEC 2017): L-SHADE with the rules below changed (optimizers/jso.cpp).
#include "optimizers/lshade.hpp"

namespace mhb::shade {

class Jso : public Lshade {
public:
    explicit Jso(const ParameterSet& p);

    Eigen::Index initial_population(int dimension) const override;
    std::pair<double, double> memory_means(int slot) const override;
    double adjusted_cr(double cr, double used) const override;
    double adjusted_f(double f, double used) const override;
    double pbest_factor(double f, double used) const override;
    double p_best_rate(double used) const override;
    bool pbest_may_be_target(double used) const override;
    std::pair<double, double> updated_memory(double old_f, double old_cr, double f_mean, double cr_mean) const override;

private:
    static Settings jso_settings(const ParameterSet& p);
};

}  // namespace mhb::shade

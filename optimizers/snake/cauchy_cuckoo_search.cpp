#include "optimizers/snake/cauchy_cuckoo_search.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "framework/input_error.hpp"
#include "optimizers/greedy_selection.hpp"

namespace mhb {

double mantegna_sigma(double beta) {
    const double numerator = std::tgamma(1.0 + beta) * std::sin(std::numbers::pi * beta / 2.0);
    const double denominator = std::tgamma((1.0 + beta) / 2.0) * beta * std::pow(2.0, (beta - 1.0) / 2.0);
    return std::pow(numerator / denominator, 1.0 / beta);
}

double mantegna_step(Rng& rng, double sigma, double beta) {
    const double u = sigma * rng.normal();
    double v = rng.normal();
    while (v == 0.0) v = rng.normal();
    return u / std::pow(std::abs(v), 1.0 / beta);
}

double cauchy_step_factor(Rng& rng, double mu) {
    return mu - 1.0 / (10.0 * std::tan(std::numbers::pi * rng.uniform_open()));
}

double step_factor(Rng& rng, double mu, CauchyAlphaRule rule) {
    double alpha = cauchy_step_factor(rng, mu);
    if (rule == CauchyAlphaRule::Raw) return alpha;
    while (alpha <= 0.0) alpha = cauchy_step_factor(rng, mu);
    return std::min(alpha, 1.0);
}

double lehmer_mean(const double* values, std::size_t count) {
    double squares = 0.0, sum = 0.0;
    for (std::size_t k = 0; k < count; ++k) {
        squares += values[k] * values[k];
        sum += values[k];
    }
    return squares / sum;
}

CauchyCuckooSearch::CauchyCuckooSearch(CauchyCuckooSettings settings)
    : settings_(settings), sigma_(mantegna_sigma(kBeta)), mu_(settings.mu0) {
    if (!(settings.mu_weight >= 0.0 && settings.mu_weight <= 1.0))
        throw ParameterError("mu_weight", "must lie in [0, 1]");
    if (!(settings.discovery_probability >= 0.0 && settings.discovery_probability <= 1.0))
        throw ParameterError("discovery_probability", "must lie in [0, 1]");
    // Under the JADE rule a non-positive location would make the redraw loop of step_factor
    // accept almost nothing.
    if (settings.alpha_rule == CauchyAlphaRule::Jade && !(settings.mu0 > 0.0))
        throw ParameterError("cauchy_mu0", "must be positive with cauchy_alpha = jade");
}

void CauchyCuckooSearch::resize(Eigen::Index dimension, Eigen::Index size) {
    (void)dimension;
    alphas_.resize(size);
    accepted_.resize(static_cast<std::size_t>(size));
    mu_ = settings_.mu0;
}

void CauchyCuckooSearch::propose_levy(const Eigen::Ref<const Matrix>& nests, const Eigen::Ref<const Vector>& best,
                                      const Bounds& bounds, Rng& rng, Eigen::Ref<Matrix> out) {
    for (Eigen::Index i = 0; i < nests.cols(); ++i) {
        const double alpha = step_factor(rng, mu_, settings_.alpha_rule);
        alphas_[i] = alpha;
        for (Eigen::Index j = 0; j < nests.rows(); ++j) {
            const double x = nests(j, i);
            out(j, i) = x + alpha * (x - best[j]) * mantegna_step(rng, sigma_, kBeta);
        }
    }
    clamp_to_bounds(out, bounds);
}

Eigen::Index CauchyCuckooSearch::accept_levy(Eigen::Ref<Matrix> nests, Eigen::Ref<Vector> fitness,
                                             const Eigen::Ref<const Matrix>& candidates,
                                             const Eigen::Ref<const Vector>& candidate_fitness) {
    const Eigen::Index replaced = greedy_replace(nests, fitness, candidates, candidate_fitness, &accepted_);
    double squares = 0.0, sum = 0.0;
    for (Eigen::Index i = 0; i < alphas_.size(); ++i) {
        if (!accepted_[static_cast<std::size_t>(i)]) continue;
        squares += alphas_[i] * alphas_[i];
        sum += alphas_[i];
    }
    // An empty success set leaves mu alone (JADE); so does a non-positive sum, possible only under
    // the raw rule, for which the Lehmer mean is no location at all.
    if (replaced > 0 && sum > 0.0) mu_ = updated_location(mu_, settings_.mu_weight, squares / sum);
    return replaced;
}

void CauchyCuckooSearch::propose_discovery(const Eigen::Ref<const Matrix>& nests, const Bounds& bounds, Rng& rng,
                                           Eigen::Ref<Matrix> out) {
    const auto n = static_cast<std::uint64_t>(nests.cols());
    const double r = rng.uniform();
    for (std::uint64_t i = 0; i < n; ++i) {
        auto p = rng.below(n - 1);
        if (p >= i) ++p;
        auto q = rng.below(n - 2);
        if (q >= std::min(i, p)) ++q;
        if (q >= std::max(i, p)) ++q;
        const auto ci = static_cast<Eigen::Index>(i), cp = static_cast<Eigen::Index>(p), cq = static_cast<Eigen::Index>(q);
        for (Eigen::Index j = 0; j < nests.rows(); ++j) {
            const double x = nests(j, ci);
            out(j, ci) = rng.uniform() > settings_.discovery_probability ? x + r * (nests(j, cp) - nests(j, cq)) : x;
        }
    }
    clamp_to_bounds(out, bounds);
}

}  // namespace mhb

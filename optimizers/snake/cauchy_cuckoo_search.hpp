#pragma once
// ISOA's third strategy (seed paper section 3.1.3, eq. 17-25): cuckoo search (Yang & Deb 2009)
// whose Lévy step factor alpha is drawn per cuckoo from a Cauchy distribution whose location mu
// adapts to the factors that worked, as JADE adapts its F.
#include <cstddef>
#include <vector>

#include "framework/optimizer.hpp"

namespace mhb {

// Mantegna's sigma_u for Lévy exponent beta: (Gamma(1+b) sin(pi b/2) / (Gamma((1+b)/2) b 2^((b-1)/2)))^(1/b).
// For beta = 1.5 it is 0.696574, a standard deviation (eq. 18 writes N(0, 0.6966)).
double mantegna_sigma(double beta);

// Eq. (18): one Lévy-stable step u / |v|^(1/beta), u ~ N(0, sigma^2), v ~ N(0, 1). A v of exactly
// zero (probability ~2^-53) is redrawn so that the step is always finite.
double mantegna_step(Rng& rng, double sigma, double beta);

// Eq. (22): alpha = mu - 1/(10 tan(pi r)), r uniform on (0, 1): exactly a Cauchy(mu, 0.1) draw.
double cauchy_step_factor(Rng& rng, double mu);

// How eq. (22)'s draws become step factors.
enum class CauchyAlphaRule {
    Jade,  // JADE's rule for F, matching the paper's "alpha in (0, 1)": redraw while <= 0, cut to 1 above 1
    Raw,   // the draw as it is, negative values included
};

double step_factor(Rng& rng, double mu, CauchyAlphaRule rule);

// Lehmer mean sum(a^2) / sum(a), the L_s of eq. (23).
double lehmer_mean(const double* values, std::size_t count);

// Eq. (23): mu <- w mu + (1 - w) L_s, with w = 0.1 in the paper (JADE keeps 0.9 of the old value).
inline double updated_location(double mu, double weight, double lehmer) {
    return weight * mu + (1.0 - weight) * lehmer;
}

struct CauchyCuckooSettings {
    double mu0 = 0.5;                     // initial location of eq. (22)
    double mu_weight = 0.1;               // w of eq. (23)
    double discovery_probability = 0.25;  // p_a of eq. (19): a coordinate moves with probability 1 - p_a
    CauchyAlphaRule alpha_rule = CauchyAlphaRule::Jade;
};

// One cuckoo population (in ISOA: one sex of the snake population) with its own mu.
class CauchyCuckooSearch {
public:
    static constexpr double kBeta = 1.5;

    explicit CauchyCuckooSearch(CauchyCuckooSettings settings);

    // Preallocates for `size` nests of dimension `dimension` and resets mu to mu0.
    void resize(Eigen::Index dimension, Eigen::Index size);

    // Eq. (17)/(24): candidate i = x_i + alpha_i (x_i - best) .* L_i, alpha_i one draw per nest, L_i
    // one Lévy step per coordinate; clamped to the box.
    void propose_levy(const Eigen::Ref<const Matrix>& nests, const Eigen::Ref<const Vector>& best, const Bounds& bounds,
                      Rng& rng, Eigen::Ref<Matrix> out);

    // Greedy acceptance of the Lévy candidates. The alphas of the accepted moves form the success
    // set of eq. (23): when it is not empty (and, under the raw rule, its sum is positive) mu moves to
    // w mu + (1 - w) L_s. Returns how many nests were replaced.
    Eigen::Index accept_levy(Eigen::Ref<Matrix> nests, Eigen::Ref<Vector> fitness,
                             const Eigen::Ref<const Matrix>& candidates, const Eigen::Ref<const Vector>& candidate_fitness);

    // Eq. (19)/(25): candidate i = x_i + r (x_p - x_q) on the coordinates that move (each with
    // probability 1 - p_a), p != q, both != i, fresh per nest; one r per pass as in Yang & Deb's
    // code. Clamped to the box. Needs at least 3 nests.
    void propose_discovery(const Eigen::Ref<const Matrix>& nests, const Bounds& bounds, Rng& rng,
                           Eigen::Ref<Matrix> out);

    double mu() const { return mu_; }
    // The alphas of the last Lévy proposal, one per nest.
    const Vector& alphas() const { return alphas_; }

private:
    CauchyCuckooSettings settings_;
    double sigma_;
    double mu_;
    Vector alphas_;
    std::vector<char> accepted_;
};

}  // namespace mhb

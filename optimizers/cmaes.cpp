// (mu/mu_w, lambda)-CMA-ES after Hansen's tutorial (arXiv:1604.00772, 2016): weighted recombination,
// cumulative step-size adaptation, rank-one and rank-mu covariance updates with the h_sigma stall,
// eigendecomposition renewed lazily. Equation numbers below are the tutorial's. The search runs in
// coordinates scaled to the unit box, which makes sigma0 a fraction of each coordinate's range.
// Boundary handling and other choices are documented in docs/baselines.md.
#include "optimizers/cmaes.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Householder>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"

namespace mhb::cmaes {

StrategyParameters default_strategy(int n, int lambda) {
    if (n < 1) throw std::invalid_argument("CMA-ES needs at least one variable");
    if (lambda != 0 && lambda < 2)
        throw ParameterError("population", "lambda must be 0 (default) or at least 2 (got " + std::to_string(lambda) + ")");
    StrategyParameters s;
    const double dn = n;
    s.lambda = lambda == 0 ? 4 + static_cast<int>(std::floor(3.0 * std::log(dn))) : lambda;  // (48)
    s.mu = s.lambda / 2;
    // (49) with the positive weights normalised to sum 1 (53); the negative weights of active CMA
    // are not used.
    s.weights.resize(s.mu);
    for (int i = 0; i < s.mu; ++i) s.weights[i] = std::log((s.lambda + 1) / 2.0) - std::log(i + 1.0);
    s.weights /= s.weights.sum();
    s.mu_eff = 1.0 / s.weights.squaredNorm();
    const double me = s.mu_eff;
    s.c_sigma = (me + 2.0) / (dn + me + 5.0);                                                   // (55)
    s.d_sigma = 1.0 + 2.0 * std::max(0.0, std::sqrt((me - 1.0) / (dn + 1.0)) - 1.0) + s.c_sigma;  // (55)
    s.c_c = (4.0 + me / dn) / (dn + 4.0 + 2.0 * me / dn);                                      // (56)
    const double alpha_cov = 2.0;
    s.c_1 = alpha_cov / ((dn + 1.3) * (dn + 1.3) + me);
    s.c_mu = std::min(1.0 - s.c_1,
                      alpha_cov * (me - 2.0 + 1.0 / me) / ((dn + 2.0) * (dn + 2.0) + alpha_cov * me / 2.0));
    s.chi_n = std::sqrt(dn) * (1.0 - 1.0 / (4.0 * dn) + 1.0 / (21.0 * dn * dn));
    return s;
}

double reflect_into(double x, double lo, double hi) {
    const double width = hi - lo;
    double t = std::fmod(std::abs(x - lo), 2.0 * width);
    if (t > width) t = 2.0 * width - t;
    return lo + t;
}

namespace {

enum class Boundary { Reflect, Clamp };

class Cmaes final : public Optimizer {
public:
    explicit Cmaes(const ParameterSet& p)
        : requested_lambda_(p.integer("population")),
          sigma0_(p.real("sigma0")),
          boundary_(p.text("boundary") == "reflect" ? Boundary::Reflect : Boundary::Clamp) {
        if (requested_lambda_ == 1)
            throw ParameterError("population", "lambda must be 0 (default) or at least 2 (got 1)");
    }

    void initialize(Evaluator& evaluator, Rng& rng) override {
        const int n = evaluator.dimension();
        s_ = default_strategy(n, static_cast<int>(requested_lambda_));
        const Eigen::Index lambda = s_.lambda;
        lower_ = evaluator.bounds().lower;
        width_ = evaluator.bounds().upper - lower_;
        mean_.resize(n);
        for (int j = 0; j < n; ++j) mean_[j] = rng.uniform();
        sigma_ = sigma0_;
        p_sigma_.setZero(n);
        p_c_.setZero(n);
        c_.setIdentity(n, n);
        b_.setIdentity(n, n);
        d_.setOnes(n);
        bd_.setIdentity(n, n);
        scratch_.resize(n, n);
        // Made in place: Eigen leaves an uncomputed solver's status unset, so copying or moving one
        // reads an indeterminate enum (UBSan reports it).
        solver_.emplace(n);
        diagonal_.resize(n);
        sub_diagonal_.resize(n - 1);
        householder_coefficients_.resize(n - 1);
        householder_workspace_.resize(n);
        z_.resize(n, lambda);
        y_.resize(n, lambda);
        candidates_.resize(n, lambda);
        fitness_.resize(lambda);
        order_.resize(static_cast<std::size_t>(lambda));
        weighted_selection_.resize(n, s_.mu);
        y_w_.resize(n);
        whitened_.resize(n);
        eigen_coordinates_.resize(n);
        generation_ = 0;
        samples_since_eigen_ = 0;
        // The tutorial renews B and D once lambda / ((c_1 + c_mu) n 10) samples have passed, which keeps
        // the O(n^3) decomposition at O(n^2) per sample.
        eigen_interval_ = static_cast<double>(lambda) / ((s_.c_1 + s_.c_mu) * n * 10.0);
        run_generation(evaluator, rng);
    }

    void iterate(const Progress&, Evaluator& evaluator, Rng& rng) override { run_generation(evaluator, rng); }

private:
    void run_generation(Evaluator& evaluator, Rng& rng) {
        const Eigen::Index n = mean_.size();
        const Eigen::Index lambda = s_.lambda;
        if (static_cast<double>(samples_since_eigen_) > eigen_interval_) decompose();

        for (Eigen::Index k = 0; k < lambda; ++k)
            for (Eigen::Index j = 0; j < n; ++j) z_(j, k) = rng.normal();
        // y_k = B D z_k ~ N(0, C)  (38-39). Products go column by column here and below: Eigen's
        // blocked matrix products take their workspace from the heap once it exceeds 128 KiB.
        for (Eigen::Index k = 0; k < lambda; ++k) y_.col(k).noalias() = bd_ * z_.col(k);
        sample_candidates(evaluator.bounds());
        evaluator.evaluate(candidates_, fitness_);

        // Ties broken by index so the ranking (and the run) is fixed by the seed.
        std::iota(order_.begin(), order_.end(), Eigen::Index{0});
        std::sort(order_.begin(), order_.end(), [this](Eigen::Index a, Eigen::Index b) {
            return fitness_[a] < fitness_[b] || (fitness_[a] == fitness_[b] && a < b);
        });

        y_w_.setZero();
        for (int i = 0; i < s_.mu; ++i) {
            const auto& y = y_.col(order_[static_cast<std::size_t>(i)]);
            y_w_ += s_.weights[i] * y;                                    // (41)
            weighted_selection_.col(i) = std::sqrt(s_.weights[i]) * y;  // for sum w_i y_i y_i^T
        }
        mean_ += sigma_ * y_w_;  // (42), c_m = 1

        const double cs = s_.c_sigma, cc = s_.c_c, me = s_.mu_eff;
        whiten(y_w_);
        p_sigma_ = (1.0 - cs) * p_sigma_ + std::sqrt(cs * (2.0 - cs) * me) * whitened_;  // (43)
        ++generation_;
        const double p_sigma_norm = p_sigma_.norm();
        // h_sigma stalls the rank-one path while ||p_sigma|| is large, i.e. while sigma is growing fast.
        const bool h_sigma = p_sigma_norm / std::sqrt(1.0 - std::pow(1.0 - cs, 2.0 * static_cast<double>(generation_))) <
                             (1.4 + 2.0 / (static_cast<double>(n) + 1.0)) * s_.chi_n;
        p_c_ = (1.0 - cc) * p_c_;
        if (h_sigma) p_c_ += std::sqrt(cc * (2.0 - cc) * me) * y_w_;  // (45)
        const double delta_h = h_sigma ? 0.0 : cc * (2.0 - cc);
        // (47) with positive weights only, so sum w_j = 1. Only the lower triangle is kept up to date
        // (rank updates without temporaries); decompose() mirrors it.
        c_.triangularView<Eigen::Lower>() *= 1.0 + s_.c_1 * delta_h - s_.c_1 - s_.c_mu;
        c_.selfadjointView<Eigen::Lower>().rankUpdate(p_c_, s_.c_1);
        for (int i = 0; i < s_.mu; ++i)
            c_.selfadjointView<Eigen::Lower>().rankUpdate(weighted_selection_.col(i), s_.c_mu);
        sigma_ *= std::exp((cs / s_.d_sigma) * (p_sigma_norm / s_.chi_n - 1.0));  // (44)
        samples_since_eigen_ += lambda;
    }

    // Maps the samples m + sigma y_k (unit-box coordinates) into the box for evaluation.
    void sample_candidates(const Bounds& bounds) {
        const Eigen::Index n = mean_.size();
        for (Eigen::Index k = 0; k < y_.cols(); ++k) {
            bool repaired = false;
            for (Eigen::Index j = 0; j < n; ++j) {
                const double u = mean_[j] + sigma_ * y_(j, k);
                double inside = u;
                if (u < 0.0 || u > 1.0) {
                    if (boundary_ == Boundary::Reflect) {
                        inside = reflect_into(u, 0.0, 1.0);
                    } else {
                        inside = std::clamp(u, 0.0, 1.0);
                        // Lamarckian repair: the step that is learnt from is the one that was evaluated.
                        y_(j, k) = (inside - mean_[j]) / sigma_;
                        repaired = true;
                    }
                }
                candidates_(j, k) = std::clamp(lower_[j] + width_[j] * inside, bounds.lower[j], bounds.upper[j]);
            }
            if (repaired) clip_mahalanobis_length(k);
        }
    }

    // A repaired step is no longer a sample of N(0, C); Hansen (2011, "Injecting external solutions
    // into CMA-ES") bounds its Mahalanobis length by sqrt(n) + 2n / (n + 2) so that it cannot inflate
    // sigma or C.
    void clip_mahalanobis_length(Eigen::Index k) {
        const double n = static_cast<double>(mean_.size());
        const double limit = std::sqrt(n) + 2.0 * n / (n + 2.0);
        whiten(y_.col(k));
        const double length = whitened_.norm();
        if (length > limit) y_.col(k) *= limit / length;
    }

    // whitened_ = C^(-1/2) y = B D^-1 B^T y, without forming C^(-1/2).
    void whiten(const Eigen::Ref<const Vector>& y) {
        eigen_coordinates_.noalias() = b_.transpose() * y;
        eigen_coordinates_.array() /= d_.array();
        whitened_.noalias() = b_ * eigen_coordinates_;
    }

    // The steps of Eigen's SelfAdjointEigenSolver::compute (scale, tridiagonalise, accumulate Q,
    // implicit QR on the tridiagonal matrix), taken one by one so that every workspace is
    // preallocated: compute() allocates per call. Eigen's own path also uses
    // internal::tridiagonalization_inplace; Q is accumulated in place, where Eigen applies the
    // reflectors one at a time with our workspace (out of place it blocks them into temporaries).
    void decompose() {
        const Eigen::Index n = c_.rows();
        for (Eigen::Index i = 0; i < n; ++i)
            for (Eigen::Index j = 0; j < i; ++j) c_(j, i) = c_(i, j);
        const double scale = c_.cwiseAbs().maxCoeff();
        scratch_ = c_ / scale;
        Eigen::internal::tridiagonalization_inplace(scratch_, householder_coefficients_);
        diagonal_ = scratch_.diagonal();
        sub_diagonal_ = scratch_.diagonal<-1>();
        Eigen::HouseholderSequence<Matrix, Vector> reflectors(scratch_, householder_coefficients_);
        reflectors.setLength(n - 1).setShift(1).evalTo(scratch_, householder_workspace_);
        solver_->computeFromTridiagonal(diagonal_, sub_diagonal_, Eigen::ComputeEigenvectors);
        if (solver_->info() != Eigen::Success)
            throw PluginFault("CMA-ES: the eigendecomposition of the covariance matrix did not converge");
        for (Eigen::Index k = 0; k < n; ++k) b_.col(k).noalias() = scratch_ * solver_->eigenvectors().col(k);
        const double largest = scale * solver_->eigenvalues().maxCoeff();
        d_ = (scale * solver_->eigenvalues()).cwiseMax(kEigenvalueFloor * largest).cwiseSqrt();
        bd_ = b_ * d_.asDiagonal();
        samples_since_eigen_ = 0;
    }

    std::int64_t requested_lambda_;
    double sigma0_;
    Boundary boundary_;
    StrategyParameters s_;
    Vector lower_, width_;
    Vector mean_;
    double sigma_ = 0.0;
    Vector p_sigma_, p_c_;
    Matrix c_, b_, bd_, scratch_;
    Vector d_;
    std::optional<Eigen::SelfAdjointEigenSolver<Matrix>> solver_;
    Vector diagonal_, sub_diagonal_, householder_coefficients_, householder_workspace_;
    Matrix z_, y_, candidates_;
    Vector fitness_;
    std::vector<Eigen::Index> order_;
    Matrix weighted_selection_;
    Vector y_w_, whitened_, eigen_coordinates_;
    std::int64_t generation_ = 0;
    std::int64_t samples_since_eigen_ = 0;
    double eigen_interval_ = 0.0;
    // Eigenvalues below this fraction of the largest are rounding noise (C's condition number has
    // then passed 1e14); they are raised to it so that C^(-1/2) stays finite.
    static constexpr double kEigenvalueFloor = 1e-14;
};

const bool registered = register_optimizer({
    "cmaes",
    "(mu/mu_w, lambda)-CMA-ES with the default parameters of Hansen's tutorial (2016)",
    {
        ParameterSpec::integer("population", 0, 0, 1'000'000, "offspring per generation lambda; 0 = 4 + floor(3 ln n)"),
        ParameterSpec::real("sigma0", 0.3, 1e-9, 10.0, "initial step size as a fraction of each coordinate's range"),
        ParameterSpec::choice("boundary", "clamp", {"clamp", "reflect"},
                              "clamp: evaluate the sample clamped into the box and learn from that point (step "
                              "length-clipped); reflect: evaluate the sample reflected into the box, learn from the "
                              "sample itself"),
    },
    [](const ParameterSet& p) { return std::make_unique<Cmaes>(p); },
});

}  // namespace
}  // namespace mhb::cmaes

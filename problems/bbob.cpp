// The 24 noiseless BBOB functions (Hansen, Finck, Ros & Auger 2009, "Real-parameter black-box
// optimization benchmarking 2009: noiseless functions definitions", INRIA RR-6829).
//
// Instances are generated the way COCO's bbob suite generates them (code-experiments/src/
// suite_bbob_legacy_code.c and f_*.c of numbbo/coco): the same legacy uniform/Gaussian generator,
// the same seeds (function + 10000 * instance, with f4 and f18 borrowing the seeds of f3 and f17),
// the same x_opt, f_opt and Gram-Schmidt rotations, and the transformations composed in the same
// order. bbob_fK(dimension=D, instance=I) is therefore COCO's problem bbob_fK_iI_dD; the tests check
// this against values COCO itself computed.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

#include "framework/registry.hpp"

namespace mhb {
namespace {

using Index = Eigen::Index;
constexpr int max_dimension = 100;
// Per-candidate work vectors live on the stack: evaluate() allocates nothing and shares nothing.
using Work = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, max_dimension, 1>;
using Column = Eigen::Ref<const Vector>;
constexpr double pi = std::numbers::pi;

// --- COCO's legacy generator (bbob2009_unif, bbob2009_gauss, ...) ---------------------------------

// A Park-Miller minimal-standard generator behind a 32-entry shuffle table (Bays-Durham).
std::vector<double> legacy_uniform(std::size_t n, std::int64_t seed) {
    if (seed < 0) seed = -seed;
    if (seed < 1) seed = 1;
    std::int64_t state = seed;
    auto advance = [&state] {
        const auto t = static_cast<std::int64_t>(std::floor(static_cast<double>(state) / 127773.0));
        state = 16807 * (state - t * 127773) - 2836 * t;
        if (state < 0) state += 2147483647;
    };
    std::array<std::int64_t, 32> table{};
    for (int i = 39; i >= 0; --i) {
        advance();
        if (i < 32) table[static_cast<std::size_t>(i)] = state;
    }
    std::int64_t pick = table[0];
    std::vector<double> r(n);
    for (std::size_t i = 0; i < n; ++i) {
        advance();
        const auto slot = static_cast<std::size_t>(std::floor(static_cast<double>(pick) / 67108865.0));
        pick = table[slot];
        table[slot] = state;
        r[i] = static_cast<double>(pick) / 2.147483647e9;
        if (r[i] == 0.0) r[i] = 1e-99;
    }
    return r;
}

// Box-Muller on 2n legacy uniforms: the first n give the radii, the last n the angles.
std::vector<double> legacy_gaussian(std::size_t n, std::int64_t seed) {
    const auto u = legacy_uniform(2 * n, seed);
    std::vector<double> g(n);
    for (std::size_t i = 0; i < n; ++i) {
        g[i] = std::sqrt(-2 * std::log(u[i])) * std::cos(2 * pi * u[n + i]);
        if (g[i] == 0.0) g[i] = 1e-99;
    }
    return g;
}

// Gram-Schmidt on the columns of a Gaussian matrix filled column by column, with COCO's loop
// order so that the rounding (and hence every instance) is COCO's.
Matrix legacy_rotation(int d, std::int64_t seed) {
    const auto g = legacy_gaussian(static_cast<std::size_t>(d) * d, seed);
    Matrix b(d, d);
    for (int i = 0; i < d; ++i)
        for (int j = 0; j < d; ++j) b(i, j) = g[static_cast<std::size_t>(j) * d + i];
    for (int i = 0; i < d; ++i) {
        for (int j = 0; j < i; ++j) {
            double prod = 0;
            for (int k = 0; k < d; ++k) prod += b(k, i) * b(k, j);
            for (int k = 0; k < d; ++k) b(k, i) -= prod * b(k, j);
        }
        double prod = 0;
        for (int k = 0; k < d; ++k) prod += b(k, i) * b(k, i);
        for (int k = 0; k < d; ++k) b(k, i) /= std::sqrt(prod);
    }
    return b;
}

// x_opt uniform on the grid 8*floor(1e4 u)/1e4 - 4 in [-4, 4), never exactly 0.
Vector legacy_xopt(int d, std::int64_t seed) {
    const auto u = legacy_uniform(static_cast<std::size_t>(d), seed);
    Vector x(d);
    for (int i = 0; i < d; ++i) {
        x[i] = 8 * std::floor(1e4 * u[static_cast<std::size_t>(i)]) / 1e4 - 4;
        if (x[i] == 0.0) x[i] = -1e-5;
    }
    return x;
}

// The seed of an instance: f4 and f18 are variants of f3 and f17 on the same instances.
std::int64_t instance_seed(int function, std::int64_t instance) {
    return (function == 4 ? 3 : function == 18 ? 17 : function) + 10000 * instance;
}

// f_opt: a ratio of two Gaussians rounded to 0.01 and clipped to [-1000, 1000].
double legacy_fopt(int function, std::int64_t instance) {
    const std::int64_t seed = instance_seed(function, instance);
    const double numerator = legacy_gaussian(1, seed)[0];
    const double denominator = legacy_gaussian(1, seed + 1)[0];
    return std::min(1000.0, std::max(-1000.0, std::floor(100.0 * 100.0 * numerator / denominator + 0.5) / 100.0));
}

// lambda_i = base^(i/(D-1)), the diagonal of Lambda^alpha with base = sqrt(alpha).
Vector conditioning(int d, double base) {
    Vector l(d);
    for (int i = 0; i < d; ++i) l[i] = std::pow(base, static_cast<double>(i) / (d - 1.0));
    return l;
}

// rot1 * diag(base^(k/(D-1))) * rot2, summed in COCO's order.
Matrix legacy_product(const Matrix& rot1, double base, const Matrix& rot2) {
    const Index d = rot1.rows();
    Matrix m = Matrix::Zero(d, d);
    for (Index i = 0; i < d; ++i)
        for (Index j = 0; j < d; ++j)
            for (Index k = 0; k < d; ++k)
                m(i, j) += rot1(i, k) * std::pow(base, static_cast<double>(k) / (d - 1.0)) * rot2(k, j);
    return m;
}

// --- transformations --------------------------------------------------------------------------------

// T_osz, written as COCO writes it (log/0.1, then the 0.1-th power).
double oscillate(double x) {
    if (x > 0) {
        const double t = std::log(x) / 0.1;
        return std::pow(std::exp(t + 0.49 * (std::sin(t) + std::sin(0.79 * t))), 0.1);
    }
    if (x < 0) {
        const double t = std::log(-x) / 0.1;
        return -std::pow(std::exp(t + 0.49 * (std::sin(0.55 * t) + std::sin(0.31 * t))), 0.1);
    }
    return 0.0;
}

void oscillate(Work& z) {
    for (Index i = 0; i < z.size(); ++i) z[i] = oscillate(z[i]);
}

// T_asy^beta: positive coordinates raised to 1 + beta * i/(D-1) * sqrt(x_i).
void asymmetric(Work& z, double beta) {
    const double d = static_cast<double>(z.size());
    for (Index i = 0; i < z.size(); ++i)
        if (z[i] > 0) z[i] = std::pow(z[i], 1.0 + beta * static_cast<double>(i) / (d - 1.0) * std::sqrt(z[i]));
}

// f_pen: squared distance outside [-5, 5]^D.
double outside_penalty(const Column& x, double bound = 5.0) {
    double p = 0;
    for (Index i = 0; i < x.size(); ++i) {
        const double t = std::abs(x[i]) - bound;
        if (t > 0) p += t * t;
    }
    return p;
}

double rastrigin(const Work& z) {
    double cosines = 0, squares = 0;
    for (Index i = 0; i < z.size(); ++i) {
        cosines += std::cos(2 * pi * z[i]);
        squares += z[i] * z[i];
    }
    return 10.0 * (static_cast<double>(z.size()) - cosines) + squares;
}

double rosenbrock(const Work& z) {
    double s1 = 0, s2 = 0;
    for (Index i = 0; i + 1 < z.size(); ++i) {
        const double a = z[i] * z[i] - z[i + 1];
        const double b = z[i] - 1.0;
        s1 += a * a;
        s2 += b * b;
    }
    return 100.0 * s1 + s2;
}

const char* function_name(int f) {
    static constexpr std::array<const char*, 24> names{
        "sphere",
        "separable ellipsoid",
        "separable Rastrigin",
        "Bueche-Rastrigin",
        "linear slope",
        "attractive sector",
        "step ellipsoid",
        "Rosenbrock",
        "rotated Rosenbrock",
        "rotated ellipsoid",
        "discus",
        "bent cigar",
        "sharp ridge",
        "different powers",
        "rotated Rastrigin",
        "Weierstrass",
        "Schaffer F7",
        "Schaffer F7, condition 1000",
        "composite Griewank-Rosenbrock F8F2",
        "Schwefel x*sin(x)",
        "Gallagher 101 peaks",
        "Gallagher 21 peaks",
        "Katsuura",
        "Lunacek bi-Rastrigin"};
    return names[static_cast<std::size_t>(f - 1)];
}

class BbobFunction final : public Problem {
public:
    BbobFunction(int function, int dimension, std::int64_t instance)
        : function_(function), d_(dimension), instance_(instance), fopt_(legacy_fopt(function, instance)) {
        set_domain(dimension, -5.0, 5.0);
        const std::int64_t seed = instance_seed(function, instance);
        truth_.optimum_value = fopt_;
        switch (function) {
            case 1: build_shifted(seed, &BbobFunction::sphere); break;
            case 2:
                build_shifted(seed, &BbobFunction::separable_ellipsoid);
                weight_ = conditioning(d_, 1e6);
                break;
            case 3:
                build_shifted(seed, &BbobFunction::separable_rastrigin);
                scale_ = conditioning(d_, std::sqrt(10.0));
                break;
            case 4:
                build_shifted(seed, &BbobFunction::bueche_rastrigin);
                // In the legacy code (not in the definitions): the odd-numbered coordinates of x_opt are >= 0.
                for (int i = 0; i < d_; i += 2) xopt_[i] = std::abs(xopt_[i]);
                truth_.true_parameters = xopt_;
                scale_ = conditioning(d_, std::sqrt(10.0));
                break;
            case 5: build_linear_slope(seed); break;
            case 6: build_conditioned(seed, &BbobFunction::attractive_sector, std::sqrt(10.0)); break;
            case 7:
                build_rotated(seed, &BbobFunction::step_ellipsoid);
                truth_.true_parameters.reset();  // flat around x_opt: not a unique minimiser
                scale_ = conditioning(d_, std::sqrt(10.0));
                weight_ = conditioning(d_, 100.0);
                break;
            case 8:
                build_shifted(seed, &BbobFunction::shifted_rosenbrock);
                xopt_ *= 0.75;
                truth_.true_parameters = xopt_;
                factor_ = std::max(1.0, std::sqrt(static_cast<double>(d_)) / 8.0);
                break;
            case 9: build_rotated_rosenbrock(seed, &BbobFunction::rotated_rosenbrock); break;
            case 10:
                build_rotated(seed, &BbobFunction::rotated_ellipsoid);
                weight_ = conditioning(d_, 1e6);
                break;
            case 11: build_rotated(seed, &BbobFunction::discus); break;
            case 12:
                build_rotated(seed, &BbobFunction::bent_cigar);
                xopt_ = legacy_xopt(d_, seed + 1000000);  // f12 alone draws x_opt from the shifted seed
                truth_.true_parameters = xopt_;
                break;
            case 13: build_conditioned(seed, &BbobFunction::sharp_ridge, std::sqrt(10.0)); break;
            case 14:
                build_rotated(seed, &BbobFunction::different_powers);
                weight_.resize(d_);
                for (int i = 0; i < d_; ++i) weight_[i] = 2.0 + 4.0 * i / (d_ - 1.0);
                break;
            case 15: build_conditioned(seed, &BbobFunction::rotated_rastrigin, std::sqrt(10.0)); break;
            case 16:
                build_conditioned(seed, &BbobFunction::weierstrass, 1.0 / std::sqrt(100.0));
                truth_.true_parameters.reset();  // every integer z is a global minimum
                break;
            case 17:
            case 18: {
                build_rotated(seed, &BbobFunction::schaffer);
                const Vector lambda = conditioning(d_, std::sqrt(function == 17 ? 10.0 : 1000.0));
                linear_ = lambda.asDiagonal() * q_;
                break;
            }
            case 19: build_rotated_rosenbrock(seed, &BbobFunction::griewank_rosenbrock); break;
            case 20: build_schwefel(seed); break;
            case 21: build_gallagher(seed, 101); break;
            case 22: build_gallagher(seed, 21); break;
            case 23:
                build_conditioned(seed, &BbobFunction::katsuura, std::sqrt(100.0));
                truth_.true_parameters.reset();  // every integer z with product 1 is a global minimum
                break;
            case 24: build_lunacek(seed); break;
            default: throw std::invalid_argument("BBOB function number must be 1..24");
        }
    }

    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        for (Index j = 0; j < x.cols(); ++j) f[j] = (this->*kernel_)(x.col(j));
    }

    std::string describe() const override {
        char fopt[32];
        std::snprintf(fopt, sizeof fopt, "%.2f", fopt_);
        return "BBOB f" + std::to_string(function_) + " " + function_name(function_) + ", instance " +
               std::to_string(instance_) + ", D=" + std::to_string(d_) + ", f_opt=" + fopt + " (COCO instance)";
    }

private:
    using Kernel = double (BbobFunction::*)(const Column&) const;

    void build_shifted(std::int64_t seed, Kernel kernel) {
        kernel_ = kernel;
        xopt_ = legacy_xopt(d_, seed);
        truth_.true_parameters = xopt_;
    }
    // R from seed + 1000000 and Q from seed: COCO's rot1 and rot2.
    void build_rotated(std::int64_t seed, Kernel kernel) {
        build_shifted(seed, kernel);
        r_ = legacy_rotation(d_, seed + 1000000);
        q_ = legacy_rotation(d_, seed);
    }
    // The map R Lambda Q with lambda_i = base^(i/(D-1)).
    void build_conditioned(std::int64_t seed, Kernel kernel, double base) {
        build_rotated(seed, kernel);
        linear_ = legacy_product(r_, base, q_);
    }
    // f5: the optimum is the corner 5*sign(x_opt), on the boundary of the box.
    void build_linear_slope(std::int64_t seed) {
        kernel_ = &BbobFunction::linear_slope;
        const Vector raw = legacy_xopt(d_, seed);
        xopt_.resize(d_);
        weight_.resize(d_);
        for (int i = 0; i < d_; ++i) {
            xopt_[i] = raw[i] < 0 ? -5.0 : 5.0;
            const double s = std::pow(std::sqrt(100.0), static_cast<double>(i) / (d_ - 1.0));
            weight_[i] = raw[i] > 0 ? s : -s;
        }
        truth_.true_parameters = xopt_;
    }
    // f9 and f19: z = max(1, sqrt(D)/8) R x + 1/2 with R from the unshifted seed; z_opt = 1.
    void build_rotated_rosenbrock(std::int64_t seed, Kernel kernel) {
        kernel_ = kernel;
        q_ = legacy_rotation(d_, seed);
        factor_ = std::max(1.0, std::sqrt(static_cast<double>(d_)) / 8.0);
        linear_ = factor_ * q_;
        xopt_.resize(d_);
        for (int c = 0; c < d_; ++c) {
            double column_sum = 0;
            for (int r = 0; r < d_; ++r) column_sum += q_(r, c);
            xopt_[c] = column_sum / (2.0 * factor_);
        }
        truth_.true_parameters = xopt_;
    }
    // f20: signs 1+- from the legacy uniforms; |x_opt| = 4.2096874637/2 as in COCO.
    void build_schwefel(std::int64_t seed) {
        kernel_ = &BbobFunction::schwefel;
        const auto u = legacy_uniform(static_cast<std::size_t>(d_), seed);
        sign_.resize(d_);
        for (int i = 0; i < d_; ++i) sign_[i] = u[static_cast<std::size_t>(i)] - 0.5 < 0 ? -1.0 : 1.0;
        xopt_ = 0.5 * schwefel_twice_abs_xopt * sign_;
        scale_ = conditioning(d_, std::sqrt(10.0));
        // The exact minimiser has every z_i at the maximiser z* = 420.968746359982 of z sin(sqrt z);
        // COCO's x_opt (from 4.2096874637) is within 1e-9 of it. Invert z(x) for z = z*.
        const double z_star = 420.968746359982;
        Vector z_hat(d_);
        for (int i = 0; i < d_; ++i)
            z_hat[i] = (z_star / 100.0 - schwefel_twice_abs_xopt) / scale_[i] + schwefel_twice_abs_xopt;
        Vector x_hat(d_);
        x_hat[0] = z_hat[0];
        for (int i = 1; i < d_; ++i) x_hat[i] = z_hat[i] - 0.25 * (x_hat[i - 1] - schwefel_twice_abs_xopt);
        truth_.true_parameters = (0.5 * x_hat.array() * sign_.array()).matrix();
    }
    void build_gallagher(std::int64_t seed, int peaks) {
        kernel_ = &BbobFunction::gallagher;
        const double b = peaks == 101 ? 10.0 : 9.8, c = peaks == 101 ? 5.0 : 4.9;
        // The best peak's condition: 1000 for 101 peaks (sqrt applied below), 1000^2 for 21.
        const double first_condition = peaks == 101 ? std::sqrt(1000.0) : 1000.0;
        q_ = legacy_rotation(d_, seed);
        auto order = [](const std::vector<double>& values) {
            std::vector<std::size_t> index(values.size());
            std::iota(index.begin(), index.end(), 0);
            std::sort(index.begin(), index.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
            return index;
        };
        const auto condition_order = order(legacy_uniform(static_cast<std::size_t>(peaks - 1), seed));
        Vector peak_condition(peaks);
        peak_height_.resize(peaks);
        peak_condition[0] = first_condition;
        peak_height_[0] = 10;
        for (int i = 1; i < peaks; ++i) {
            peak_condition[i] = std::pow(1000.0, static_cast<double>(condition_order[static_cast<std::size_t>(i - 1)]) /
                                                     (peaks - 2.0));
            peak_height_[i] = static_cast<double>(i - 1) / (peaks - 2.0) * (9.1 - 1.1) + 1.1;
        }
        peak_scale_.resize(d_, peaks);
        for (int i = 0; i < peaks; ++i) {
            const auto axis_order = order(legacy_uniform(static_cast<std::size_t>(d_), seed + 1000 * i));
            for (int j = 0; j < d_; ++j)
                peak_scale_(j, i) = std::pow(
                    peak_condition[i], static_cast<double>(axis_order[static_cast<std::size_t>(j)]) / (d_ - 1.0) - 0.5);
        }
        const auto u = legacy_uniform(static_cast<std::size_t>(d_) * peaks, seed);
        xopt_.resize(d_);
        peak_centre_.resize(d_, peaks);  // stored rotated: centre_p = R y_p
        for (int i = 0; i < d_; ++i) {
            xopt_[i] = 0.8 * (b * u[static_cast<std::size_t>(i)] - c);
            for (int j = 0; j < peaks; ++j) {
                double s = 0;
                for (int k = 0; k < d_; ++k) s += q_(i, k) * (b * u[static_cast<std::size_t>(j * d_ + k)] - c);
                peak_centre_(i, j) = j == 0 ? 0.8 * s : s;
            }
        }
        truth_.true_parameters = xopt_;
    }
    // f24: x_opt = mu0/2 * 1+- with the signs of legacy Gaussians.
    void build_lunacek(std::int64_t seed) {
        kernel_ = &BbobFunction::lunacek;
        r_ = legacy_rotation(d_, seed + 1000000);
        q_ = legacy_rotation(d_, seed);
        const auto g = legacy_gaussian(static_cast<std::size_t>(d_), seed);
        xopt_.resize(d_);
        for (int i = 0; i < d_; ++i) xopt_[i] = g[static_cast<std::size_t>(i)] < 0 ? -0.5 * lunacek_mu0 : 0.5 * lunacek_mu0;
        scale_ = conditioning(d_, std::sqrt(100.0));
        truth_.true_parameters = xopt_;
    }

    Work shifted(const Column& x) const { return x - xopt_; }
    Work rotated(const Matrix& m, const Work& y) const {
        Work z(d_);
        z.noalias() = m * y;
        return z;
    }

    double sphere(const Column& x) const { return (x - xopt_).squaredNorm() + fopt_; }

    double separable_ellipsoid(const Column& x) const {
        Work z = shifted(x);
        oscillate(z);
        return (weight_.array() * z.array().square()).sum() + fopt_;
    }

    double separable_rastrigin(const Column& x) const {
        Work z = shifted(x);
        oscillate(z);
        asymmetric(z, 0.2);
        z.array() *= scale_.array();
        return rastrigin(z) + fopt_;
    }

    double bueche_rastrigin(const Column& x) const {
        Work z = shifted(x);
        oscillate(z);
        for (Index i = 0; i < d_; ++i) z[i] *= (z[i] > 0 && i % 2 == 0) ? 10.0 * scale_[i] : scale_[i];
        return rastrigin(z) + fopt_ + 100.0 * outside_penalty(x);
    }

    // COCO evaluates the slope without the definitions' clipping at x_opt; inside [-5,5]^D the two agree.
    double linear_slope(const Column& x) const {
        return (5.0 * weight_.array().abs() - weight_.array() * x.array()).sum() + fopt_;
    }

    double attractive_sector(const Column& x) const {
        const Work z = rotated(linear_, shifted(x));
        double s = 0;
        for (Index i = 0; i < d_; ++i) s += (xopt_[i] * z[i] > 0 ? 100.0 * 100.0 : 1.0) * z[i] * z[i];
        return std::pow(oscillate(s), 0.9) + fopt_;
    }

    double step_ellipsoid(const Column& x) const {
        Work z_hat = rotated(q_, shifted(x));
        z_hat.array() *= scale_.array();
        const double first = z_hat[0];
        for (Index i = 0; i < d_; ++i)
            z_hat[i] = std::abs(z_hat[i]) > 0.5 ? std::floor(z_hat[i] + 0.5) : std::floor(10.0 * z_hat[i] + 0.5) / 10.0;
        const Work z = rotated(r_, z_hat);
        const double ellipsoid = (weight_.array() * z.array().square()).sum();
        return 0.1 * std::max(std::abs(first) * 1.0e-4, ellipsoid) + outside_penalty(x) + fopt_;
    }

    double shifted_rosenbrock(const Column& x) const {
        Work z = shifted(x);
        z = (factor_ * z.array() + 1.0).matrix();
        return rosenbrock(z) + fopt_;
    }

    double rotated_rosenbrock(const Column& x) const {
        Work z(d_);
        z.noalias() = linear_ * x;
        z.array() += 0.5;
        return rosenbrock(z) + fopt_;
    }

    double rotated_ellipsoid(const Column& x) const {
        Work z = rotated(r_, shifted(x));
        oscillate(z);
        return (weight_.array() * z.array().square()).sum() + fopt_;
    }

    double discus(const Column& x) const {
        Work z = rotated(r_, shifted(x));
        oscillate(z);
        return 1.0e6 * z[0] * z[0] + z.tail(d_ - 1).squaredNorm() + fopt_;
    }

    double bent_cigar(const Column& x) const {
        Work y = rotated(r_, shifted(x));
        asymmetric(y, 0.5);
        const Work z = rotated(r_, y);
        return z[0] * z[0] + 1.0e6 * z.tail(d_ - 1).squaredNorm() + fopt_;
    }

    double sharp_ridge(const Column& x) const {
        const Work z = rotated(linear_, shifted(x));
        return 100.0 * z.tail(d_ - 1).norm() + z[0] * z[0] + fopt_;
    }

    double different_powers(const Column& x) const {
        const Work z = rotated(r_, shifted(x));
        double s = 0;
        for (Index i = 0; i < d_; ++i) s += std::pow(std::abs(z[i]), weight_[i]);
        return std::sqrt(s) + fopt_;
    }

    double rotated_rastrigin(const Column& x) const {
        Work y = rotated(r_, shifted(x));
        oscillate(y);
        asymmetric(y, 0.2);
        return rastrigin(rotated(linear_, y)) + fopt_;
    }

    double weierstrass(const Column& x) const {
        Work y = rotated(r_, shifted(x));
        oscillate(y);
        const Work z = rotated(linear_, y);
        double s = 0;
        for (Index i = 0; i < d_; ++i)
            for (std::size_t k = 0; k < weierstrass_terms; ++k)
                s += std::cos(2 * pi * (z[i] + 0.5) * weierstrass_frequency[k]) * weierstrass_amplitude[k];
        return 10.0 * std::pow(s / d_ - weierstrass_offset, 3.0) + fopt_ + 10.0 / d_ * outside_penalty(x);
    }

    double schaffer(const Column& x) const {
        Work y = rotated(r_, shifted(x));
        asymmetric(y, 0.5);
        const Work z = rotated(linear_, y);
        double s = 0;
        for (Index i = 0; i + 1 < d_; ++i) {
            const double t = z[i] * z[i] + z[i + 1] * z[i + 1];
            s += std::pow(t, 0.25) * (1.0 + std::pow(std::sin(50.0 * std::pow(t, 0.1)), 2.0));
        }
        return std::pow(s / (d_ - 1.0), 2.0) + fopt_ + 10.0 * outside_penalty(x);
    }

    double griewank_rosenbrock(const Column& x) const {
        Work z(d_);
        z.noalias() = linear_ * x;
        z.array() += 0.5;
        double s = 0;
        for (Index i = 0; i + 1 < d_; ++i) {
            const double a = z[i] * z[i] - z[i + 1];
            const double b = 1.0 - z[i];
            const double t = 100.0 * a * a + b * b;
            s += t / 4000.0 - std::cos(t);
        }
        return 10.0 + 10.0 * s / (d_ - 1.0) + fopt_;
    }

    double schwefel(const Column& x) const {
        Work x_hat = (2.0 * sign_.array() * x.array()).matrix();
        Work z(d_);
        z[0] = x_hat[0];
        for (Index i = 1; i < d_; ++i) z[i] = x_hat[i] + 0.25 * (x_hat[i - 1] - schwefel_twice_abs_xopt);
        z = (100.0 * (scale_.array() * (z.array() - schwefel_twice_abs_xopt) + schwefel_twice_abs_xopt)).matrix();
        double penalty = 0, sum = 0;
        for (Index i = 0; i < d_; ++i) {
            const double t = std::abs(z[i]) - 500.0;
            if (t > 0) penalty += t * t;
            sum += z[i] * std::sin(std::sqrt(std::abs(z[i])));
        }
        return 0.01 * (penalty + 418.9828872724339 - sum / d_) + fopt_;
    }

    double gallagher(const Column& x) const {
        Work y(d_);
        y.noalias() = q_ * x;
        double best = 0;
        for (Index p = 0; p < peak_centre_.cols(); ++p) {
            const double d2 = (peak_scale_.col(p).array() * (y - peak_centre_.col(p)).array().square()).sum();
            best = std::max(best, peak_height_[p] * std::exp(-0.5 / d_ * d2));
        }
        const double g = oscillate(10.0 - best);
        return g * g + outside_penalty(x) + fopt_;
    }

    double katsuura(const Column& x) const {
        const Work z = rotated(linear_, shifted(x));
        double product = 1.0;
        for (Index i = 0; i < d_; ++i) {
            double s = 0;
            for (double two_j = 2.0; two_j <= 4294967296.0; two_j *= 2.0)  // 2^1 .. 2^32, exact
                s += std::abs(two_j * z[i] - std::floor(two_j * z[i] + 0.5)) / two_j;
            product *= 1.0 + (static_cast<double>(i) + 1.0) * s;
        }
        const double d = d_;
        return 10.0 / d / d * (-1.0 + std::pow(product, 10.0 / std::pow(d, 1.2))) + fopt_ + outside_penalty(x);
    }

    double lunacek(const Column& x) const {
        const double d = d_;
        const double s = 1.0 - 0.5 / (std::sqrt(d + 20.0) - 4.1);
        const double mu1 = -std::sqrt((lunacek_mu0 * lunacek_mu0 - 1.0) / s);
        Work x_hat(d_);
        for (Index i = 0; i < d_; ++i) x_hat[i] = xopt_[i] < 0 ? -2.0 * x[i] : 2.0 * x[i];
        Work y = rotated(q_, (x_hat.array() - lunacek_mu0).matrix());
        y.array() *= scale_.array();
        const Work z = rotated(r_, y);
        const double near = (x_hat.array() - lunacek_mu0).square().sum();
        const double far = (x_hat.array() - mu1).square().sum();
        const double cosines = (2 * pi * z.array()).cos().sum();
        return std::min(near, d + s * far) + 10.0 * (d - cosines) + 1e4 * outside_penalty(x) + fopt_;
    }

    static constexpr double schwefel_twice_abs_xopt = 4.2096874637;
    static constexpr double lunacek_mu0 = 2.5;
    static constexpr std::size_t weierstrass_terms = 12;
    static constexpr std::array<double, 12> weierstrass_amplitude{1.0,       0.5,        0.25,        0.125,
                                                                  0.0625,    0.03125,    0.015625,    0.0078125,
                                                                  0.00390625, 0.001953125, 0.0009765625, 0.00048828125};
    static constexpr std::array<double, 12> weierstrass_frequency{1, 3, 9, 27, 81, 243, 729, 2187, 6561, 19683, 59049, 177147};
    // f0 = sum_k 0.5^k cos(pi 3^k) = -(2 - 2^-11), the value of the Weierstrass sum at z = 0.
    static constexpr double weierstrass_offset = -1.99951171875;

    int function_;
    int d_;
    std::int64_t instance_;
    double fopt_;
    Kernel kernel_ = nullptr;
    Vector xopt_;
    Matrix r_, q_;       // rotations from seed + 1000000 and from seed
    Matrix linear_;      // the function's combined linear map (e.g. R Lambda Q)
    Vector scale_;       // a diagonal conditioning Lambda
    Vector weight_;      // per-coordinate weights of the final sum
    Vector sign_;        // f20: the 1+- vector
    double factor_ = 1;  // f8, f9, f19: max(1, sqrt(D)/8)
    Matrix peak_scale_, peak_centre_;  // f21, f22: one column per peak
    Vector peak_height_;
};

const bool registered = [] {
    for (int f = 1; f <= 24; ++f) {
        register_problem(
            {"bbob_f" + std::to_string(f),
             std::string("BBOB 2009 ") + function_name(f) + ", [-5,5]^D, COCO instances",
             {ParameterSpec::integer("dimension", 10, 2, max_dimension, "number of variables"),
              ParameterSpec::integer("instance", 1, 1, 100'000, "COCO instance number (x_opt, f_opt, rotations)")},
             [f](const ParameterSet& p, const ProblemContext&) -> std::unique_ptr<Problem> {
                 return std::make_unique<BbobFunction>(f, static_cast<int>(p.integer("dimension")),
                                                       p.integer("instance"));
             }});
    }
    return true;
}();

}  // namespace
}  // namespace mhb

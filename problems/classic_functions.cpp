// The 23 classic test functions F1-F23 of Yao, Liu & Lin (1999), "Evolutionary programming made
// faster", IEEE Trans. Evol. Comput. 3(2), with the bounds and dimensions of their tables and of the
// GWO (Mirjalili 2014) and Snake Optimizer (Hashim & Hussien 2022) code. Choices where the popular
// code and the paper differ (F6, F20) are documented in docs/test-functions.md.
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "framework/registry.hpp"

namespace mhb {
namespace {

using Index = Eigen::Index;
using Kernel = void (*)(const Eigen::Ref<const Matrix>&, Eigen::Ref<Vector>);
constexpr double pi = std::numbers::pi;

// max of z·sin(sqrt(z)) on [0, 500], reached at z = 420.968746359982 (root of
// sin(sqrt z) + sqrt(z)/2·cos(sqrt z) = 0, solved by bisection to double precision).
constexpr double schwefel_minimiser = 420.968746359982;
constexpr double schwefel_minimum_per_coordinate = -418.98288727243374;

// --- F1-F13: scalable -----------------------------------------------------------------------------

void sphere(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    f = x.array().square().colwise().sum().transpose();
}

void schwefel_2_22(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    for (Index j = 0; j < x.cols(); ++j) {
        const auto a = x.col(j).array().abs();
        f[j] = a.sum() + a.prod();
    }
}

void schwefel_1_2(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    for (Index j = 0; j < x.cols(); ++j) {
        double prefix = 0.0, total = 0.0;
        for (Index i = 0; i < x.rows(); ++i) {
            prefix += x(i, j);
            total += prefix * prefix;
        }
        f[j] = total;
    }
}

void schwefel_2_21(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    f = x.array().abs().colwise().maxCoeff().transpose();
}

void rosenbrock(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    const Index d = x.rows();
    const auto head = x.topRows(d - 1).array();
    const auto tail = x.bottomRows(d - 1).array();
    f = (100.0 * (tail - head.square()).square() + (head - 1.0).square()).colwise().sum().transpose();
}

// Yao's F6: the step function sum(floor(x + 0.5)^2), flat on [-0.5, 0.5)^D.
void step(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    f = (x.array() + 0.5).floor().square().colwise().sum().transpose();
}

// F6 as written in the GWO/SO code: sum(|x + 0.5|^2), a sphere shifted to -0.5, without the floor.
void step_without_floor(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    f = (x.array() + 0.5).square().colwise().sum().transpose();
}

void quartic_without_noise(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    const Index d = x.rows();
    for (Index j = 0; j < x.cols(); ++j)
        f[j] = (Eigen::ArrayXd::LinSpaced(d, 1.0, static_cast<double>(d)) * x.col(j).array().square().square()).sum();
}

void schwefel_2_26(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    f = -(x.array() * x.array().abs().sqrt().sin()).colwise().sum().transpose();
}

void rastrigin(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    f = (x.array().square() - 10.0 * (2.0 * pi * x.array()).cos() + 10.0).colwise().sum().transpose();
}

void ackley(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    const double d = static_cast<double>(x.rows());
    for (Index j = 0; j < x.cols(); ++j) {
        const auto c = x.col(j).array();
        f[j] = -20.0 * std::exp(-0.2 * std::sqrt(c.square().sum() / d)) - std::exp((2.0 * pi * c).cos().sum() / d) +
               20.0 + std::numbers::e;
    }
}

void griewank(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    const Index d = x.rows();
    for (Index j = 0; j < x.cols(); ++j) {
        const auto c = x.col(j).array();
        f[j] = c.square().sum() / 4000.0 -
               (c / Eigen::ArrayXd::LinSpaced(d, 1.0, static_cast<double>(d)).sqrt()).cos().prod() + 1.0;
    }
}

// u(x, a, k, m) of Yao's F12/F13, a penalty outside [-a, a]; both use m = 4.
double boundary_penalty(double x, double a, double k) {
    const double excess = x > a ? x - a : x < -a ? -x - a : 0.0;
    return k * (excess * excess) * (excess * excess);
}

double square(double v) { return v * v; }

void penalized_1(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    const Index d = x.rows();
    for (Index j = 0; j < x.cols(); ++j) {
        // y_i = 1 + (x_i + 1)/4
        auto y = [&](Index i) { return 1.0 + (x(i, j) + 1.0) / 4.0; };
        double s = 10.0 * square(std::sin(pi * y(0)));
        for (Index i = 0; i + 1 < d; ++i)
            s += square(y(i) - 1.0) * (1.0 + 10.0 * square(std::sin(pi * y(i + 1))));
        s += square(y(d - 1) - 1.0);
        double penalty = 0.0;
        for (Index i = 0; i < d; ++i) penalty += boundary_penalty(x(i, j), 10.0, 100.0);
        f[j] = pi / static_cast<double>(d) * s + penalty;
    }
}

void penalized_2(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    const Index d = x.rows();
    for (Index j = 0; j < x.cols(); ++j) {
        double s = square(std::sin(3.0 * pi * x(0, j)));
        for (Index i = 0; i + 1 < d; ++i)
            s += square(x(i, j) - 1.0) * (1.0 + square(std::sin(3.0 * pi * x(i + 1, j))));
        s += square(x(d - 1, j) - 1.0) * (1.0 + square(std::sin(2.0 * pi * x(d - 1, j))));
        double penalty = 0.0;
        for (Index i = 0; i < d; ++i) penalty += boundary_penalty(x(i, j), 5.0, 100.0);
        f[j] = 0.1 * s + penalty;
    }
}

// --- F14-F23: fixed dimension, constants of Yao et al. 1999 ------------------------------------------

void shekel_foxholes(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    static constexpr std::array<double, 5> grid{-32.0, -16.0, 0.0, 16.0, 32.0};
    for (Index j = 0; j < x.cols(); ++j) {
        double s = 1.0 / 500.0;
        for (int k = 0; k < 25; ++k) {
            const double a1 = grid[k % 5], a2 = grid[k / 5];
            s += 1.0 / (k + 1 + std::pow(x(0, j) - a1, 6) + std::pow(x(1, j) - a2, 6));
        }
        f[j] = 1.0 / s;
    }
}

void kowalik(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    static constexpr std::array<double, 11> a{0.1957, 0.1947, 0.1735, 0.1600, 0.0844, 0.0627,
                                              0.0456, 0.0342, 0.0323, 0.0235, 0.0246};
    static constexpr std::array<double, 11> inverse_b{0.25, 0.5, 1, 2, 4, 6, 8, 10, 12, 14, 16};
    for (Index j = 0; j < x.cols(); ++j) {
        double s = 0.0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            const double b = 1.0 / inverse_b[i];
            const double model = x(0, j) * (b * b + x(1, j) * b) / (b * b + x(2, j) * b + x(3, j));
            s += (a[i] - model) * (a[i] - model);
        }
        f[j] = s;
    }
}

void six_hump_camel(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    for (Index j = 0; j < x.cols(); ++j) {
        const double a = x(0, j), b = x(1, j);
        f[j] = 4 * a * a - 2.1 * std::pow(a, 4) + std::pow(a, 6) / 3 + a * b - 4 * b * b + 4 * std::pow(b, 4);
    }
}

void branin(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    for (Index j = 0; j < x.cols(); ++j) {
        const double a = x(0, j), b = x(1, j);
        const double r = b - 5.1 / (4 * pi * pi) * a * a + 5 / pi * a - 6;
        f[j] = r * r + 10 * (1 - 1 / (8 * pi)) * std::cos(a) + 10;
    }
}

void goldstein_price(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    for (Index j = 0; j < x.cols(); ++j) {
        const double a = x(0, j), b = x(1, j);
        f[j] = (1 + (a + b + 1) * (a + b + 1) * (19 - 14 * a + 3 * a * a - 14 * b + 6 * a * b + 3 * b * b)) *
               (30 + (2 * a - 3 * b) * (2 * a - 3 * b) * (18 - 32 * a + 12 * a * a + 48 * b - 36 * a * b + 27 * b * b));
    }
}

// Hartmann's family: -sum_i c_i exp(-sum_j a_ij (x_j - p_ij)^2).
template <int D>
struct HartmannConstants {
    std::array<std::array<double, D>, 4> a;
    std::array<std::array<double, D>, 4> p;
};
constexpr std::array<double, 4> hartmann_c{1.0, 1.2, 3.0, 3.2};

// p_41 = 0.03815 as in Yao's table and the GWO code: it puts the minimum at the published
// (0.114614, 0.555649, 0.852547), -3.86278 (with 0.0381 it would sit at x_1 = 0.114589).
constexpr HartmannConstants<3> hartmann_3{
    {{{3, 10, 30}, {0.1, 10, 35}, {3, 10, 30}, {0.1, 10, 35}}},
    {{{0.3689, 0.1170, 0.2673}, {0.4699, 0.4387, 0.7470}, {0.1091, 0.8732, 0.5547}, {0.03815, 0.5743, 0.8828}}}};

// p_32 = 0.1451, the Hartmann constant that gives the published minimum -3.32237 at
// (0.20169, 0.150011, 0.476874, 0.275332, 0.311652, 0.6573).
constexpr HartmannConstants<6> hartmann_6{
    {{{10, 3, 17, 3.5, 1.7, 8}, {0.05, 10, 17, 0.1, 8, 14}, {3, 3.5, 1.7, 10, 17, 8}, {17, 8, 0.05, 10, 0.1, 14}}},
    {{{0.1312, 0.1696, 0.5569, 0.0124, 0.8283, 0.5886},
      {0.2329, 0.4135, 0.8307, 0.3736, 0.1004, 0.9991},
      {0.2348, 0.1451, 0.3522, 0.2883, 0.3047, 0.6650},
      {0.4047, 0.8828, 0.8732, 0.5743, 0.1091, 0.0381}}}};

// The GWO/SO code writes p_32 = 0.1415; that moves the minimum to -3.32199517 at x_2 = 0.14678.
constexpr HartmannConstants<6> hartmann_6_gwo_code{
    hartmann_6.a,
    {{{0.1312, 0.1696, 0.5569, 0.0124, 0.8283, 0.5886},
      {0.2329, 0.4135, 0.8307, 0.3736, 0.1004, 0.9991},
      {0.2348, 0.1415, 0.3522, 0.2883, 0.3047, 0.6650},
      {0.4047, 0.8828, 0.8732, 0.5743, 0.1091, 0.0381}}}};

template <int D, const HartmannConstants<D>& K>
void hartmann(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    for (Index j = 0; j < x.cols(); ++j) {
        double s = 0.0;
        for (int i = 0; i < 4; ++i) {
            double e = 0.0;
            for (int k = 0; k < D; ++k) e += K.a[i][k] * (x(k, j) - K.p[i][k]) * (x(k, j) - K.p[i][k]);
            s -= hartmann_c[i] * std::exp(-e);
        }
        f[j] = s;
    }
}

// Shekel's family S_{4,m}: -sum_{i<m} 1/(|x - a_i|^2 + c_i).
template <int M>
void shekel(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) {
    static constexpr std::array<std::array<double, 4>, 10> a{{{4, 4, 4, 4},
                                                             {1, 1, 1, 1},
                                                             {8, 8, 8, 8},
                                                             {6, 6, 6, 6},
                                                             {3, 7, 3, 7},
                                                             {2, 9, 2, 9},
                                                             {5, 5, 3, 3},
                                                             {8, 1, 8, 1},
                                                             {6, 2, 6, 2},
                                                             {7, 3.6, 7, 3.6}}};
    static constexpr std::array<double, 10> c{0.1, 0.2, 0.2, 0.4, 0.4, 0.6, 0.3, 0.7, 0.5, 0.5};
    for (Index j = 0; j < x.cols(); ++j) {
        double s = 0.0;
        for (int i = 0; i < M; ++i) {
            double d2 = c[i];
            for (int k = 0; k < 4; ++k) d2 += (x(k, j) - a[i][k]) * (x(k, j) - a[i][k]);
            s -= 1.0 / d2;
        }
        f[j] = s;
    }
}

// --- problems ---------------------------------------------------------------------------------------

class ClassicFunction final : public Problem {
public:
    ClassicFunction(std::string description, Kernel kernel, Vector lower, Vector upper, KnownTruth truth)
        : description_(std::move(description)), kernel_(kernel) {
        set_domain(std::move(lower), std::move(upper));
        truth_ = std::move(truth);
    }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override { kernel_(x, f); }
    std::string describe() const override { return description_; }

private:
    std::string description_;
    Kernel kernel_;
};

// F7: the quartic plus a uniform [0, 1) draw per evaluation. The generator is seeded from the
// trial's ProblemContext::seed and advanced by evaluate(), so an instance belongs to one trial and
// must not be shared between threads; the framework creates one per trial.
class NoisyQuartic final : public Problem {
public:
    NoisyQuartic(int dimension, std::uint64_t seed) : noise_(seed) {
        set_domain(dimension, -1.28, 1.28);
        truth_.optimum_value = 0.0;  // the infimum: the noise is >= 0 and the quartic is 0 at 0
        truth_.true_parameters = Vector::Zero(dimension);
    }
    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        quartic_without_noise(x, f);
        for (Index j = 0; j < f.size(); ++j) f[j] += noise_.uniform();
    }
    std::string describe() const override {
        return "Yao et al. 1999 F7: quartic sum(i x_i^4) plus uniform [0,1) noise per evaluation";
    }

private:
    mutable Rng noise_;
};

ParameterSpec dimension_parameter() {
    return ParameterSpec::integer("dimension", 30, 2, 10'000, "number of variables (30 in Yao et al. and GWO/SO)");
}

// Registers one of F1-F13: box [-bound, bound]^D, minimum D*optimum_per_coordinate, minimiser the
// constant vector `minimiser` when it is unique.
void register_scalable(const char* name, const char* summary, Kernel kernel, double bound,
                       double optimum_per_coordinate, std::optional<double> minimiser) {
    register_problem({name, summary, {dimension_parameter()},
                      [=](const ParameterSet& p, const ProblemContext&) -> std::unique_ptr<Problem> {
                          const auto d = static_cast<int>(p.integer("dimension"));
                          KnownTruth truth;
                          truth.optimum_value = optimum_per_coordinate * d;
                          if (minimiser) truth.true_parameters = Vector::Constant(d, *minimiser);
                          return std::make_unique<ClassicFunction>(std::string(name) + ": " + summary, kernel,
                                                                   Vector::Constant(d, -bound),
                                                                   Vector::Constant(d, bound), std::move(truth));
                      }});
}

void register_fixed(const char* name, const char* summary, Kernel kernel, Vector lower, Vector upper,
                    double optimum, std::optional<Vector> minimiser) {
    register_problem({name, summary, {},
                      [=](const ParameterSet&, const ProblemContext&) -> std::unique_ptr<Problem> {
                          KnownTruth truth;
                          truth.optimum_value = optimum;
                          truth.true_parameters = minimiser;
                          return std::make_unique<ClassicFunction>(std::string(name) + ": " + summary, kernel, lower,
                                                                   upper, std::move(truth));
                      }});
}

Vector values(std::initializer_list<double> v) {
    Vector out(static_cast<Index>(v.size()));
    Index i = 0;
    for (double x : v) out[i++] = x;
    return out;
}

const bool registered = [] {
    register_scalable("F1", "sphere sum(x^2), [-100,100]^D", sphere, 100, 0, 0.0);
    register_scalable("F2", "Schwefel 2.22 sum|x| + prod|x|, [-10,10]^D", schwefel_2_22, 10, 0, 0.0);
    register_scalable("F3", "Schwefel 1.2 sum_i (sum_{j<=i} x_j)^2, [-100,100]^D", schwefel_1_2, 100, 0, 0.0);
    register_scalable("F4", "Schwefel 2.21 max|x_i|, [-100,100]^D", schwefel_2_21, 100, 0, 0.0);
    register_scalable("F5", "Rosenbrock, [-30,30]^D, minimum at 1", rosenbrock, 30, 0, 1.0);
    register_scalable("F6", "step sum(floor(x+0.5)^2) as in Yao et al., [-100,100]^D, flat minimum", step, 100, 0,
                      std::nullopt);
    register_scalable("F6_no_floor", "F6 of the GWO/SO code: sum((x+0.5)^2) without the floor, minimum at -0.5",
                      step_without_floor, 100, 0, -0.5);
    register_problem({"F7", "quartic sum(i x_i^4) + uniform [0,1) noise, [-1.28,1.28]^D", {dimension_parameter()},
                      [](const ParameterSet& p, const ProblemContext& context) -> std::unique_ptr<Problem> {
                          return std::make_unique<NoisyQuartic>(static_cast<int>(p.integer("dimension")),
                                                                context.seed);
                      }});
    register_scalable("F8", "Schwefel 2.26 -sum x sin(sqrt|x|), [-500,500]^D, minimum -418.98*D at 420.97",
                      schwefel_2_26, 500, schwefel_minimum_per_coordinate, schwefel_minimiser);
    register_scalable("F9", "Rastrigin, [-5.12,5.12]^D", rastrigin, 5.12, 0, 0.0);
    register_scalable("F10", "Ackley, [-32,32]^D", ackley, 32, 0, 0.0);
    register_scalable("F11", "Griewank, [-600,600]^D", griewank, 600, 0, 0.0);
    register_scalable("F12", "generalised penalized function 1, [-50,50]^D, minimum at -1", penalized_1, 50, 0, -1.0);
    register_scalable("F13", "generalised penalized function 2, [-50,50]^D, minimum at 1", penalized_2, 50, 0, 1.0);

    // Minima below: the published values, refined by Newton's method on these exact constants.
    register_fixed("F14", "Shekel's foxholes, D=2, [-65.536,65.536]^2", shekel_foxholes,
                   Vector::Constant(2, -65.536), Vector::Constant(2, 65.536), 0.9980038377944498,
                   values({-31.97833484, -31.97833484}));
    register_fixed("F15", "Kowalik, D=4, [-5,5]^4", kowalik, Vector::Constant(4, -5), Vector::Constant(4, 5),
                   3.074859878056e-4, values({0.19283345, 0.19083631, 0.12311731, 0.13576602}));
    register_fixed("F16", "six-hump camel back, D=2, [-5,5]^2, two minimisers", six_hump_camel,
                   Vector::Constant(2, -5), Vector::Constant(2, 5), -1.0316284534898772, std::nullopt);
    register_fixed("F17", "Branin, D=2, [-5,10]x[0,15], three minimisers", branin, values({-5, 0}),
                   values({10, 15}), 0.39788735772973816, std::nullopt);
    register_fixed("F18", "Goldstein-Price, D=2, [-2,2]^2", goldstein_price, Vector::Constant(2, -2),
                   Vector::Constant(2, 2), 3.0, values({0, -1}));
    register_fixed("F19", "Hartmann 3, D=3, [0,1]^3", hartmann<3, hartmann_3>, Vector::Zero(3), Vector::Ones(3),
                   -3.862782147820755, values({0.11461434, 0.55564885, 0.85254695}));
    register_problem(
        {"F20",
         "Hartmann 6, D=6, [0,1]^6",
         {ParameterSpec::choice("constants", "hartmann", {"hartmann", "gwo_code"},
                                "p_32 = 0.1451 (Hartmann, published optimum) or 0.1415 (GWO/SO code)")},
         [](const ParameterSet& p, const ProblemContext&) -> std::unique_ptr<Problem> {
             const bool gwo = p.text("constants") == "gwo_code";
             KnownTruth truth;
             truth.optimum_value = gwo ? -3.3219951715842417 : -3.322368011415515;
             truth.true_parameters = gwo ? values({0.20170762, 0.14678095, 0.47674485, 0.27534239, 0.31165188, 0.65727516})
                                         : values({0.20168951, 0.15001069, 0.47687397, 0.27533243, 0.31165162, 0.65730053});
             return std::make_unique<ClassicFunction>(
                 gwo ? "F20: Hartmann 6 with the GWO/SO code's p_32 = 0.1415" : "F20: Hartmann 6 (p_32 = 0.1451)",
                 gwo ? hartmann<6, hartmann_6_gwo_code> : hartmann<6, hartmann_6>, Vector::Zero(6), Vector::Ones(6),
                 std::move(truth));
         }});
    register_fixed("F21", "Shekel 5, D=4, [0,10]^4", shekel<5>, Vector::Zero(4), Vector::Constant(4, 10),
                   -10.153199679058229, values({4.00003715, 4.00013328, 4.00003715, 4.00013328}));
    register_fixed("F22", "Shekel 7, D=4, [0,10]^4", shekel<7>, Vector::Zero(4), Vector::Constant(4, 10),
                   -10.402940566818659, values({4.00057292, 4.00068937, 3.99948971, 3.99960616}));
    register_fixed("F23", "Shekel 10, D=4, [0,10]^4", shekel<10>, Vector::Zero(4), Vector::Constant(4, 10),
                   -10.536409816692043, values({4.00074653, 4.00059293, 3.99966340, 3.99950980}));
    return true;
}();

}  // namespace
}  // namespace mhb

#include "problems/cec/cec_basic_functions.hpp"

#include <array>
#include <cmath>
#include <utility>

namespace mhb::cec {
namespace {

// The organisers' constants, as they wrote them (not std::numbers, which may round differently).
constexpr double pi = 3.1415926535897932384626433832795029;
constexpr double e = 2.7182818284590452353602874713526625;

double squared(double v) { return v * v; }

// Levy on w; the two suites compute w differently (docs/test-functions.md).
double levy_of(const double* w, int n) {
    const double first = std::pow(std::sin(pi * w[0]), 2);
    const double last = std::pow(w[n - 1] - 1, 2) * (1 + std::pow(std::sin(2 * pi * w[n - 1]), 2));
    double sum = 0.0;
    for (int i = 0; i < n - 1; ++i) sum += std::pow(w[i] - 1, 2) * (1 + 10 * std::pow(std::sin(pi * w[i] + 1), 2));
    return first + sum + last;
}

constexpr int max_dimension = 100;

// |z - 1|^2 and sum(z - 1): HappyCat and HGBat have their optimum at z = -1 of the shifted point.
std::pair<double, double> squares_and_sum_around_one(const double* z, int n) {
    double r2 = 0.0, sum = 0.0;
    for (int i = 0; i < n; ++i) {
        const double v = z[i] - 1.0;
        r2 += v * v;
        sum += v;
    }
    return {r2, sum};
}

}  // namespace

double bent_cigar(const double* z, const double*, int n) {
    double f = z[0] * z[0];
    for (int i = 1; i < n; ++i) f += 1e6 * z[i] * z[i];
    return f;
}

double sum_of_different_powers(const double* z, const double*, int n) {
    double f = 0.0;
    for (int i = 0; i < n; ++i) f += std::pow(std::fabs(z[i]), i + 1);
    return f;
}

double zakharov(const double* z, const double*, int n) {
    double squares = 0.0, weighted = 0.0;
    for (int i = 0; i < n; ++i) {
        squares += z[i] * z[i];
        weighted += 0.5 * (i + 1) * z[i];
    }
    return squares + std::pow(weighted, 2) + std::pow(weighted, 4);
}

double rosenbrock(const double* z, const double*, int n) {
    double f = 0.0;
    for (int i = 0; i < n - 1; ++i) {
        const double a = z[i] + 1.0, b = z[i + 1] + 1.0;
        const double t1 = a * a - b, t2 = a - 1.0;
        f += 100.0 * t1 * t1 + t2 * t2;
    }
    return f;
}

double rastrigin(const double* z, const double*, int n) {
    double f = 0.0;
    for (int i = 0; i < n; ++i) f += z[i] * z[i] - 10.0 * std::cos(2.0 * pi * z[i]) + 10.0;
    return f;
}

double schaffer_f7(const double*, const double* u, int n) {
    double f = 0.0;
    for (int i = 0; i < n - 1; ++i) {
        const double s = std::pow(u[i] * u[i] + u[i + 1] * u[i + 1], 0.5);
        const double t = std::sin(50.0 * std::pow(s, 0.2));
        f += std::pow(s, 0.5) + std::pow(s, 0.5) * t * t;
    }
    return f * f / (n - 1) / (n - 1);
}

double lunacek_bi_rastrigin(const double* z, const double* u, int n) {
    constexpr double mu0 = 2.5, d = 1.0;
    const double s = 1.0 - 1.0 / (2.0 * std::pow(n + 20.0, 0.5) - 8.2);
    const double mu1 = -std::pow((mu0 * mu0 - d) / s, 0.5);
    double near = 0.0, far = 0.0, cosines = 0.0;
    for (int i = 0; i < n; ++i) {
        const double x_hat = u[i] + mu0;  // as the C code, which adds mu0 and subtracts it again
        near += squared(x_hat - mu0);
        far += squared(x_hat - mu1);
        cosines += std::cos(2.0 * pi * z[i]);
    }
    far = far * s + d * n;
    return std::min(near, far) + 10.0 * (n - cosines);
}

double levy_cec2017(const double* z, const double*, int n) {
    std::array<double, max_dimension> w;
    for (int i = 0; i < n; ++i) w[static_cast<std::size_t>(i)] = 1.0 + (z[i] - 1.0) / 4.0;
    return levy_of(w.data(), n);
}

double levy_cec2022(const double* z, const double*, int n) {
    std::array<double, max_dimension> w;
    for (int i = 0; i < n; ++i) w[static_cast<std::size_t>(i)] = 1.0 + (z[i] - 0.0) / 4.0;
    return levy_of(w.data(), n);
}

double modified_schwefel(const double* z, const double*, int n) {
    double f = 0.0;
    for (int i = 0; i < n; ++i) {
        const double v = z[i] + 4.209687462275036e+002;
        if (v > 500) {
            const double folded = 500.0 - std::fmod(v, 500);
            f -= folded * std::sin(std::pow(folded, 0.5));
            const double t = (v - 500.0) / 100;
            f += t * t / n;
        } else if (v < -500) {
            const double rest = std::fmod(std::fabs(v), 500);
            f -= (-500.0 + rest) * std::sin(std::pow(500.0 - rest, 0.5));
            const double t = (v + 500.0) / 100;
            f += t * t / n;
        } else {
            f -= v * std::sin(std::pow(std::fabs(v), 0.5));
        }
    }
    return f + 4.189828872724338e+002 * n;
}

double high_conditioned_elliptic(const double* z, const double*, int n) {
    double f = 0.0;
    for (int i = 0; i < n; ++i) f += std::pow(10.0, 6.0 * i / (n - 1)) * z[i] * z[i];
    return f;
}

double discus(const double* z, const double*, int n) {
    double f = 1e6 * z[0] * z[0];
    for (int i = 1; i < n; ++i) f += z[i] * z[i];
    return f;
}

double ackley(const double* z, const double*, int n) {
    double squares = 0.0, cosines = 0.0;
    for (int i = 0; i < n; ++i) {
        squares += z[i] * z[i];
        cosines += std::cos(2.0 * pi * z[i]);
    }
    return e - 20.0 * std::exp(-0.2 * std::sqrt(squares / n)) - std::exp(cosines / n) + 20.0;
}

double weierstrass(const double* z, const double*, int n) {
    constexpr int terms = 21;  // k = 0..20, a = 0.5, b = 3: both powers exact in double
    double f = 0.0, at_zero = 0.0;
    for (int i = 0; i < n; ++i) {
        double sum = 0.0, a_k = 1.0, b_k = 1.0;
        at_zero = 0.0;
        for (int k = 0; k < terms; ++k) {
            sum += a_k * std::cos(2.0 * pi * b_k * (z[i] + 0.5));
            at_zero += a_k * std::cos(2.0 * pi * b_k * 0.5);
            a_k *= 0.5;
            b_k *= 3.0;
        }
        f += sum;
    }
    return f - n * at_zero;
}

double griewank(const double* z, const double*, int n) {
    double s = 0.0, p = 1.0;
    for (int i = 0; i < n; ++i) {
        s += z[i] * z[i];
        p *= std::cos(z[i] / std::sqrt(1.0 + i));
    }
    return 1.0 + s / 4000.0 - p;
}

double katsuura(const double* z, const double*, int n) {
    const double exponent = 10.0 / std::pow(1.0 * n, 1.2);
    double f = 1.0;
    for (int i = 0; i < n; ++i) {
        double sum = 0.0, two_j = 1.0;
        for (int j = 1; j <= 32; ++j) {
            two_j *= 2.0;  // 2^j, exact
            const double t = two_j * z[i];
            sum += std::fabs(t - std::floor(t + 0.5)) / two_j;
        }
        f *= std::pow(1.0 + (i + 1) * sum, exponent);
    }
    const double scale = 10.0 / n / n;
    return f * scale - scale;
}

double happycat(const double* z, const double*, int n) {
    const auto [r2, sum] = squares_and_sum_around_one(z, n);
    return std::pow(std::fabs(r2 - n), 2 * (1.0 / 8.0)) + (0.5 * r2 + sum) / n + 0.5;
}

double hgbat(const double* z, const double*, int n) {
    const auto [r2, sum] = squares_and_sum_around_one(z, n);
    return std::pow(std::fabs(std::pow(r2, 2.0) - std::pow(sum, 2.0)), 2 * (1.0 / 4.0)) + (0.5 * r2 + sum) / n + 0.5;
}

double griewank_rosenbrock(const double* z, const double*, int n) {
    auto term = [](double a, double b) {
        const double t1 = a * a - b, t2 = a - 1.0;
        const double t = 100.0 * t1 * t1 + t2 * t2;
        return (t * t) / 4000.0 - std::cos(t) + 1.0;
    };
    double f = 0.0;
    for (int i = 0; i < n - 1; ++i) f += term(z[i] + 1.0, z[i + 1] + 1.0);
    return f + term(z[n - 1] + 1.0, z[0] + 1.0);
}

double expanded_schaffer_f6(const double* z, const double*, int n) {
    auto g = [](double a, double b) {
        const double r2 = a * a + b * b;
        double s = std::sin(std::sqrt(r2));
        s = s * s;
        const double t = 1.0 + 0.001 * r2;
        return 0.5 + (s - 0.5) / (t * t);
    };
    double f = 0.0;
    for (int i = 0; i < n - 1; ++i) f += g(z[i], z[i + 1]);
    return f + g(z[n - 1], z[0]);
}

}  // namespace mhb::cec

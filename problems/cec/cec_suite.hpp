#pragma once
// What the CEC 2017 and 2022 suites are made of, and the problem that evaluates one of their
// functions. A suite's file (cec2017.cpp, cec2022.cpp) lists its functions as Definitions; the
// shifting, rotating, shuffling and composing here are the same for both, as in the organisers' code.
//
// A population is transformed with one matrix product per rotation (Z = M (X - o) for the whole
// D x N block), then each column goes through the basic function.
#include <string>
#include <variant>
#include <vector>

#include "problems/cec/cec_basic_functions.hpp"

namespace mhb::cec {

// A basic function and the factor the organisers scale (x - o) by before rotating it.
struct Basic {
    BasicFunction function;
    double scale = 1.0;
};

// The basic functions with the factors both suites' code scales them by, written as it writes them.
inline constexpr Basic bent_cigar_g{&bent_cigar};
inline constexpr Basic zakharov_g{&zakharov};
inline constexpr Basic rosenbrock_g{&rosenbrock, 2.048 / 100.0};
inline constexpr Basic rastrigin_g{&rastrigin, 5.12 / 100.0};
inline constexpr Basic schaffer_f7_g{&schaffer_f7};
inline constexpr Basic lunacek_g{&lunacek_bi_rastrigin, 10.0 / 100.0};
inline constexpr Basic schwefel_g{&modified_schwefel, 1000.0 / 100.0};
inline constexpr Basic elliptic_g{&high_conditioned_elliptic};
inline constexpr Basic discus_g{&discus};
inline constexpr Basic ackley_g{&ackley};
inline constexpr Basic weierstrass_g{&weierstrass, 0.5 / 100.0};
inline constexpr Basic griewank_g{&griewank, 600.0 / 100.0};
inline constexpr Basic katsuura_g{&katsuura, 5.0 / 100.0};
inline constexpr Basic happycat_g{&happycat, 5.0 / 100.0};
inline constexpr Basic hgbat_g{&hgbat, 5.0 / 100.0};
inline constexpr Basic griewank_rosenbrock_g{&griewank_rosenbrock, 5.0 / 100.0};
inline constexpr Basic schaffer_f6_g{&expanded_schaffer_f6};

// Variables shuffled, then cut into consecutive groups of ceil(share * D) (the last takes the rest),
// one basic function each.
struct Hybrid {
    std::vector<std::pair<Basic, double>> parts;  // basic function, share of the variables
};

// One component g_k of a composition: its own shift o_k and rotation M_k, its weight's width
// sigma_k, its bias, and lambda_k written as the organisers write it: numerator * g / denominator.
struct Component {
    std::variant<Basic, Hybrid> g;
    double sigma;
    double bias;
    double numerator = 1.0;
    double denominator = 1.0;
    bool rotated = true;  // CEC2022 F9 and F10 leave one component unrotated
};

using Composition = std::vector<Component>;

struct Definition {
    int number;                       // as in the organisers' code
    std::string name;                 // "Shifted and Rotated Zakharov"
    double optimum;                   // F*, the bias: f(x*) = F*
    std::variant<Basic, Hybrid, Composition> formula;
    std::vector<int> dimensions;      // where the organisers' data define it
    std::string note;                 // shown after the name in `mhbench list`
};

// Registers `<suite>_f<number>` for each definition, with parameters `dimension` and `data`.
bool register_suite(const std::string& suite, const std::string& title, const std::vector<Definition>& definitions);

}  // namespace mhb::cec

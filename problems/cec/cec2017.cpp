// The CEC 2017 single-objective bound-constrained suite (Awad, Ali, Liang, Qu & Suganthan, technical
// report, 2016), F1-F30 numbered and computed as in the organisers' code (cec17_test_func.cpp), which
// differs from the report in places: docs/test-functions.md lists where.
#include "problems/cec/cec_suite.hpp"

namespace mhb::cec {
namespace {

// Hybrids 5-9 are also the components of F29 and F30.
const Hybrid hybrid5{{{bent_cigar_g, 0.2}, {hgbat_g, 0.2}, {rastrigin_g, 0.3}, {rosenbrock_g, 0.3}}};
const Hybrid hybrid6{{{schaffer_f6_g, 0.2}, {hgbat_g, 0.2}, {rosenbrock_g, 0.3}, {schwefel_g, 0.3}}};
const Hybrid hybrid7{
    {{katsuura_g, 0.1}, {ackley_g, 0.2}, {griewank_rosenbrock_g, 0.2}, {schwefel_g, 0.2}, {rastrigin_g, 0.3}}};
const Hybrid hybrid8{{{elliptic_g, 0.2}, {ackley_g, 0.2}, {rastrigin_g, 0.2}, {hgbat_g, 0.2}, {discus_g, 0.2}}};
const Hybrid hybrid9{
    {{bent_cigar_g, 0.2}, {rastrigin_g, 0.2}, {griewank_rosenbrock_g, 0.2}, {weierstrass_g, 0.2}, {schaffer_f6_g, 0.2}}};

const std::vector<int> all_dimensions{2, 10, 20, 30, 50, 100};
const std::vector<int> without_2_and_20{10, 30, 50, 100};
const std::vector<int> without_2{10, 20, 30, 50, 100};

const std::vector<Definition>& definitions() {
    static const std::vector<Definition> list{
        {1, "Shifted and Rotated Bent Cigar", 100, bent_cigar_g, all_dimensions, ""},
        {2, "Shifted and Rotated Sum of Different Power", 200, Basic{&sum_of_different_powers}, all_dimensions,
         "excluded by the organisers: unstable"},
        {3, "Shifted and Rotated Zakharov", 300, zakharov_g, all_dimensions, ""},
        {4, "Shifted and Rotated Rosenbrock", 400, rosenbrock_g, all_dimensions, ""},
        {5, "Shifted and Rotated Rastrigin", 500, rastrigin_g, all_dimensions, ""},
        {6, "Shifted Schaffer F7 (unrotated in the organisers' code)", 600, schaffer_f7_g, all_dimensions, ""},
        {7, "Shifted and Rotated Lunacek Bi-Rastrigin", 700, lunacek_g, all_dimensions, ""},
        {8, "Shifted and Rotated Non-Continuous Rastrigin (continuous in the organisers' code)", 800, rastrigin_g,
         all_dimensions, ""},
        {9, "Shifted and Rotated Levy", 900, Basic{&levy_cec2017}, all_dimensions,
         "minimum at o + M^T 1, f(o) > 900 (organisers' code)"},
        {10, "Shifted and Rotated Schwefel", 1000, schwefel_g, all_dimensions, ""},
        {11, "Hybrid Function 1 (Zakharov, Rosenbrock, Rastrigin)", 1100,
         Hybrid{{{zakharov_g, 0.2}, {rosenbrock_g, 0.4}, {rastrigin_g, 0.4}}}, without_2_and_20, ""},
        {12, "Hybrid Function 2 (Elliptic, Schwefel, Bent Cigar)", 1200,
         Hybrid{{{elliptic_g, 0.3}, {schwefel_g, 0.3}, {bent_cigar_g, 0.4}}}, without_2_and_20, ""},
        {13, "Hybrid Function 3 (Bent Cigar, Rosenbrock, Lunacek)", 1300,
         Hybrid{{{bent_cigar_g, 0.3}, {rosenbrock_g, 0.3}, {lunacek_g, 0.4}}}, without_2_and_20, ""},
        {14, "Hybrid Function 4 (Elliptic, Ackley, Schaffer F7, Rastrigin)", 1400,
         Hybrid{{{elliptic_g, 0.2}, {ackley_g, 0.2}, {schaffer_f7_g, 0.2}, {rastrigin_g, 0.4}}}, without_2_and_20, ""},
        {15, "Hybrid Function 5 (Bent Cigar, HGBat, Rastrigin, Rosenbrock)", 1500, hybrid5, without_2_and_20, ""},
        {16, "Hybrid Function 6 (Expanded Schaffer F6, HGBat, Rosenbrock, Schwefel)", 1600, hybrid6, without_2_and_20, ""},
        {17, "Hybrid Function 7 (Katsuura, Ackley, Griewank-Rosenbrock, Schwefel, Rastrigin)", 1700, hybrid7,
         without_2_and_20, ""},
        {18, "Hybrid Function 8 (Elliptic, Ackley, Rastrigin, HGBat, Discus)", 1800, hybrid8, without_2_and_20, ""},
        {19, "Hybrid Function 9 (Bent Cigar, Rastrigin, Griewank-Rosenbrock, Weierstrass, Expanded Schaffer F6)", 1900,
         hybrid9, without_2_and_20, ""},
        {20, "Hybrid Function 10 (HGBat, Katsuura, Ackley, Rastrigin, Schwefel, Schaffer F7)", 2000,
         Hybrid{{{hgbat_g, 0.1}, {katsuura_g, 0.1}, {ackley_g, 0.2}, {rastrigin_g, 0.2}, {schwefel_g, 0.2},
                 {schaffer_f7_g, 0.2}}},
         without_2, ""},
        {21, "Composition Function 1 (Rosenbrock, Elliptic, Rastrigin)", 2100,
         Composition{{rosenbrock_g, 10, 0}, {elliptic_g, 20, 100, 10000, 1e+10}, {rastrigin_g, 30, 200}}, without_2, ""},
        {22, "Composition Function 2 (Rastrigin, Griewank, Schwefel)", 2200,
         Composition{{rastrigin_g, 10, 0}, {griewank_g, 20, 100, 1000, 100}, {schwefel_g, 30, 200}}, without_2, ""},
        {23, "Composition Function 3 (Rosenbrock, Ackley, Schwefel, Rastrigin)", 2300,
         Composition{{rosenbrock_g, 10, 0}, {ackley_g, 20, 100, 1000, 100}, {schwefel_g, 30, 200}, {rastrigin_g, 40, 300}},
         all_dimensions, ""},
        {24, "Composition Function 4 (Ackley, Elliptic, Griewank, Rastrigin)", 2400,
         Composition{{ackley_g, 10, 0, 1000, 100},
                     {elliptic_g, 20, 100, 10000, 1e+10},
                     {griewank_g, 30, 200, 1000, 100},
                     {rastrigin_g, 40, 300}},
         all_dimensions, ""},
        {25, "Composition Function 5 (Rastrigin, HappyCat, Ackley, Discus, Rosenbrock)", 2500,
         Composition{{rastrigin_g, 10, 0, 10000, 1e+3},
                     {happycat_g, 20, 100, 1000, 1e+3},
                     {ackley_g, 30, 200, 1000, 100},
                     {discus_g, 40, 300, 10000, 1e+10},
                     {rosenbrock_g, 50, 400}},
         all_dimensions, ""},
        {26, "Composition Function 6 (Expanded Schaffer F6, Schwefel, Griewank, Rosenbrock, Rastrigin)", 2600,
         Composition{{schaffer_f6_g, 10, 0, 10000, 2e+7},
                     {schwefel_g, 20, 100},
                     {griewank_g, 20, 200, 1000, 100},
                     {rosenbrock_g, 30, 300},
                     {rastrigin_g, 40, 400, 10000, 1e+3}},
         all_dimensions, ""},
        {27, "Composition Function 7 (HGBat, Rastrigin, Schwefel, Bent Cigar, Elliptic, Expanded Schaffer F6)", 2700,
         Composition{{hgbat_g, 10, 0, 10000, 1000},
                     {rastrigin_g, 20, 100, 10000, 1e+3},
                     {schwefel_g, 30, 200, 10000, 4e+3},
                     {bent_cigar_g, 40, 300, 10000, 1e+30},
                     {elliptic_g, 50, 400, 10000, 1e+10},
                     {schaffer_f6_g, 60, 500, 10000, 2e+7}},
         all_dimensions, ""},
        {28, "Composition Function 8 (Ackley, Griewank, Discus, Rosenbrock, HappyCat, Expanded Schaffer F6)", 2800,
         Composition{{ackley_g, 10, 0, 1000, 100},
                     {griewank_g, 20, 100, 1000, 100},
                     {discus_g, 30, 200, 10000, 1e+10},
                     {rosenbrock_g, 40, 300},
                     {happycat_g, 50, 400, 1000, 1e+3},
                     {schaffer_f6_g, 60, 500, 10000, 2e+7}},
         all_dimensions, ""},
        {29, "Composition Function 9 (Hybrid Functions 5, 6, 7)", 2900,
         Composition{{hybrid5, 10, 0}, {hybrid6, 30, 100}, {hybrid7, 50, 200}}, without_2_and_20, ""},
        {30, "Composition Function 10 (Hybrid Functions 5, 8, 9)", 3000,
         Composition{{hybrid5, 10, 0}, {hybrid8, 30, 100}, {hybrid9, 50, 200}}, without_2_and_20, ""},
    };
    return list;
}

const bool registered = register_suite("cec2017", "CEC 2017", definitions());

}  // namespace
}  // namespace mhb::cec

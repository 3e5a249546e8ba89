// The CEC 2022 single-objective bound-constrained suite (Kumar, Price, Mohamed, Hadi & Suganthan,
// technical report, 2021), F1-F12 computed as in the organisers' code (cec22_test_func.cpp), which
// differs from the report in places: docs/test-functions.md lists where.
#include "problems/cec/cec_suite.hpp"

namespace mhb::cec {
namespace {

const std::vector<int> all_dimensions{2, 10, 20};
const std::vector<int> without_2{10, 20};

const std::vector<Definition>& definitions() {
    static const std::vector<Definition> list{
        {1, "Shifted and full Rotated Zakharov", 300, zakharov_g, all_dimensions, ""},
        {2, "Shifted and full Rotated Rosenbrock", 400, rosenbrock_g, all_dimensions, ""},
        {3, "Shifted Schaffer F7 (the report's Expanded Schaffer f6; unrotated in the organisers' code)", 600,
         schaffer_f7_g, all_dimensions, ""},
        {4, "Shifted and full Rotated Non-Continuous Rastrigin (continuous in the organisers' code)", 800, rastrigin_g,
         all_dimensions, ""},
        {5, "Shifted and full Rotated Levy", 900, Basic{&levy_cec2022}, all_dimensions, ""},
        {6, "Hybrid Function 1 (Bent Cigar, HGBat, Rastrigin)", 1800,
         Hybrid{{{bent_cigar_g, 0.4}, {hgbat_g, 0.4}, {rastrigin_g, 0.2}}}, without_2, ""},
        {7, "Hybrid Function 2 (HGBat, Katsuura, Ackley, Rastrigin, Schwefel, Schaffer F7)", 2000,
         Hybrid{{{hgbat_g, 0.1}, {katsuura_g, 0.2}, {ackley_g, 0.2}, {rastrigin_g, 0.2}, {schwefel_g, 0.1},
                 {schaffer_f7_g, 0.2}}},
         without_2, ""},
        {8, "Hybrid Function 3 (Katsuura, HappyCat, Griewank-Rosenbrock, Schwefel, Ackley)", 2200,
         Hybrid{{{katsuura_g, 0.3}, {happycat_g, 0.2}, {griewank_rosenbrock_g, 0.2}, {schwefel_g, 0.1}, {ackley_g, 0.2}}},
         without_2, ""},
        {9, "Composition Function 1 (Rosenbrock, Elliptic, Bent Cigar, Discus, Elliptic)", 2300,
         Composition{{rosenbrock_g, 10, 0, 10000, 1e+4},
                     {elliptic_g, 20, 200, 10000, 1e+10},
                     {bent_cigar_g, 30, 300, 10000, 1e+30},
                     {discus_g, 40, 100, 10000, 1e+10},
                     {elliptic_g, 50, 400, 10000, 1e+10, false}},
         all_dimensions, ""},
        {10, "Composition Function 2 (Schwefel, Rastrigin, HGBat)", 2400,
         Composition{{schwefel_g, 20, 0, 1, 1, false}, {rastrigin_g, 10, 200}, {hgbat_g, 10, 100}}, all_dimensions, ""},
        {11, "Composition Function 3 (Expanded Schaffer F6, Schwefel, Griewank, Rosenbrock, Rastrigin)", 2600,
         Composition{{schaffer_f6_g, 20, 0, 10000, 2e+7},
                     {schwefel_g, 20, 200},
                     {griewank_g, 30, 300, 1000, 100},
                     {rosenbrock_g, 30, 400},
                     {rastrigin_g, 20, 200, 10000, 1e+3}},
         all_dimensions, ""},
        {12, "Composition Function 4 (HGBat, Rastrigin, Schwefel, Bent Cigar, Elliptic, Expanded Schaffer F6)", 2700,
         Composition{{hgbat_g, 10, 0, 10000, 1000},
                     {rastrigin_g, 20, 300, 10000, 1e+3},
                     {schwefel_g, 30, 500, 10000, 4e+3},
                     {bent_cigar_g, 40, 100, 10000, 1e+30},
                     {elliptic_g, 50, 400, 10000, 1e+10},
                     {schaffer_f6_g, 60, 200, 10000, 2e+7}},
         all_dimensions, ""},
    };
    return list;
}

const bool registered = register_suite("cec2022", "CEC 2022", definitions());

}  // namespace
}  // namespace mhb::cec

#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "framework/trial.hpp"

using namespace mhb;

namespace {

std::unique_ptr<Problem> bbob(int function, std::int64_t dimension, std::int64_t instance = 1) {
    return make_problem("bbob_f" + std::to_string(function), {{"dimension", dimension}, {"instance", instance}});
}

double at(const Problem& p, const Vector& x) {
    Vector f(1);
    p.evaluate(x, f);
    return f[0];
}

struct CocoValue {
    int function;
    int instance;
    std::vector<double> x;
    double f;
};

// Values computed by COCO itself: numbbo/coco, code-experiments/test/regression-test/data/
// regression_test_2data_for_suite_bbob.py (commit 1bb9287b). Its keys are suite problem indices
// k = instance_index + 15 * (function - 1) + 360 * dimension_index over dimensions (2, 3, 5, 10, 20, 40);
// only instance indices 0-4 (instances 1-5, the same in every COCO year) are used here.
const std::vector<CocoValue> coco_values{
    {1, 1, {0.12260794261231554, 0.044699779575631919, -0.34931779381027933}, 81.080938447762335},  // k=360
    {1, 1, {13.382317228473649, 10.13915864997532, -12.670622241727648, 21.616498180472121, 47.318782398113612},
     3409.8428938036641},  // k=720
    {2, 4, {-0.062879390165237095, -1.7783300315498827, -2.2367347879177029, 3.6214790063499538, -2.7120790689257612},
     1159373.9058300618},  // k=738
    {3, 1, {0.3880986175959239, -1.0102090325630915, -0.037114701772910812, -0.054617866780047035, -0.42790314432297455},
     -293.72170457240748},                                                                            // k=750
    {3, 5, {0.85456301226369891, 0.23428555905143855}, 200.31670460007004},                           // k=34
    {3, 5, {-0.13836312584565544, -0.0062699120128144915, 0.30241968560881705}, 277.44938441488182},  // k=394
    {4, 1,
     {-0.27274711930265672, -1.7323072286189416, -0.59051812044358831, 1.1513995553020884, 0.039743062782827375,
      1.9399764817648582, -1.0691844497400784, 2.342911487711183, 1.231824268399095, 0.89427272062847618},
     -166.09388640027845},                                                                             // k=1125
    {5, 5, {0.13575375752784852, -0.18542552177416743, -0.20005936334009852}, 35.812595161846545},     // k=424
    {5, 4, {-0.35539464619768657, -0.097253660020707136, -0.21356195621706334}, 1013.9540701403618},   // k=423
    {6, 3, {-13.970673659422706, -1.0206948487510619, 3.6770626809236622, -4.1208665865535909, -1.6407017247730142},
     32263.786884340625},                                                                              // k=797
    {7, 3, {-0.15589564659987321, -1.0591918840804744}, 1136.0032451796758},                           // k=92
    {7, 4, {0.067862264536740435, -0.10292484982771082}, 259.98320259223669},                          // k=93
    {7, 1,
     {0.07127896933514466, 0.069338680590770724, -0.24502386531612247, -0.10644094505932154, -0.0028361810880690869,
      -0.1177946802769979, 0.019156043745721999, -0.077308988685629867, -0.16250002729183, 0.054619761400912223},
     850.09425447190688},  // k=1170
    {8, 3, {0.73111731314370854, 1.1540624651251867, -0.82155345662572554, 0.36306217304240085, -0.40230989664875688},
     35960.260096793354},  // k=827
    {8, 2, {1.2579000735524155, -2.1961863772335661, 1.8347552279387873, -0.43607717435406373, 2.0441330453415625},
     81860.605301034229},                                                                               // k=826
    {9, 4, {-0.1312288906422803, 0.30606056563875489}, -90.099326082029492},                            // k=123
    {9, 4, {-0.89222203091800611, 3.4349868793399665, 1.271336000123148}, 12659.365274499965},          // k=483
    {10, 3, {0.21128720030087789, 2.1260343430227158, -1.6946222457322055}, 6370665.3429419538},        // k=497
    {10, 5, {-0.10302420048693195, 0.19148965845790877}, 9462134.3515544124},                           // k=139
    {11, 1, {0.0038909526511235987, -0.00025843556830110231, 0.0051249331094613817}, 11326030.27865451},  // k=510
    {11, 4, {1.9361136676810644, -1.5014043871608866}, 20918782.066791113},                             // k=153
    {11, 1, {-0.1288954087137284, -0.19181872516871498}, 9002903.6676527001},                           // k=150
    {11, 1, {0.024215380789838755, -0.48759183703593673}, 8088923.5264998069},                          // k=150
    {12, 2, {-0.010677645622718232, -0.035406508907044359, 0.045672484833287147}, 54445154.770492151},  // k=526
    {12, 3, {-0.95544321164350832, 1.3711789569529362}, 401501186.44412392},                            // k=167
    {12, 1, {-4.2278959721652356, -1.6885127570788971, -1.4775704769442872, 1.9373072892887242, -0.95335302992566706},
     156461914.77699107},                                                                               // k=885
    {13, 4, {-0.48527734685953461, 0.14582002833024926}, 1158.4171691629858},                           // k=183
    {13, 2, {0.20550759110750233, 0.16814545132798861}, 36.28797457861652},                             // k=181
    {13, 3, {-0.75018054490826702, -0.60717070079152036}, 189.21598650900251},                          // k=182
    {14, 4, {-0.29748149218593301, -0.60194396702417319}, 45.572363184703732},                          // k=198
    {14, 1, {2.2314669048728875, 1.7933215291338855, 0.33415482526506357, 1.4897106126213058, 1.0169266073466121},
     196.22869255511682},                                                                               // k=915
    {15, 4, {0.16910123313217323, 0.37681326152768796, -0.020489763470826899}, 437.73848529647807},     // k=573
    {15, 4, {0.86338349350750954, 0.27026661394997964}, 304.54113867225078},                            // k=213
    {16, 1, {0.24384009861472034, -0.27982451711979583, 0.037647439486215739, 0.2089305439270969, 0.37673339317286125},
     174.47130680590973},  // k=945
    {16, 1,
     {4.4902050543853571, 7.5047932738821164, -3.5555615146332227, -4.3292029801932195, 1.8467130069479889,
      -3.8299962019875129, 2.2002880747616422, -3.4871378643186968, 4.3150367713006501, 3.79228151118381},
     181.87051648429971},                                                                               // k=1305
    {17, 4, {0.32598204350746929, -0.12240041586110581}, 64.360558825508548},                           // k=243
    {17, 2, {-0.78416573291133829, 0.9842306542390149, 1.4004376633019893}, 33.942314618832462},        // k=601
    {18, 3, {-2.3236829137046375, -0.29582281565743079}, 383.11822241109655},                           // k=257
    {18, 1, {0.0090382986014505735, 0.30236885032987804, -1.2088300912574275}, 96.111343882177493},     // k=615
    {18, 2, {1.3634593604243859, 21.789966558345142}, 3770.8326686774517},                              // k=256
    {18, 5, {0.17796471006581557, 0.03186263898305107}, -72.176649475003245},                           // k=259
    {19, 5, {-0.49667307898834967, -1.1591344588994257}, -611.68409518868827},                          // k=274
    {19, 2,
     {1.5657791034241229, 0.10930405165583502, 0.37863861929176051, -5.144732009363806, 3.6120114690235079,
      -6.4636391405477553, 10.672361818228318, -3.639874498721396, 2.2581396494056474, 6.5424864117997759},
     409.93314374036737},                                                                               // k=1351
    {20, 4, {0.0048986955219583435, -0.058883889844767175, -0.30151061772558796}, 2810.5952970229873},  // k=648
    {20, 4,
     {-0.038605858668216794, 0.6092340576271319, 0.42721790117607311, -0.46365391518047933, 0.47676006019462913,
      0.79696925593486667, 0.37016535083289021, 0.2669678945324041, -0.044835525234019805, -0.7246080703918375},
     18110.675863887533},  // k=1368
    {21, 1, {3.6472217223054555, -3.9785310018064211, -3.7791315682464774, -9.2294643938015017, 1.7179725043474665},
     142.31188369733121},                                                                               // k=1020
    {21, 2, {-0.0060400531773042799, 0.18134741311175115, 0.063260617424276924}, 12.918395773565544},   // k=661
    {22, 1, {3.3264855485234435, 1.7400953117761022, -4.0137419365273939}, -985.91195555025649},        // k=675
    {22, 2, {1.3047361391760659, 1.0721587410969771}, 1014.9354295014659},                              // k=316
    {22, 5, {12.916075653972836, -1.1951597544645336}, 199.75899811111813},                             // k=319
    {23, 3, {0.094812294860924226, 0.33238069179051011}, -104.73656135785458},                          // k=332
    {23, 4, {0.054664465076689969, 0.0038247183269724473, 0.0050028076042338086, -0.01160979023506252, 0.24351156140149319},
     -210.07597929189794},  // k=1053
    {23, 5, {2.2637627440173715, 1.5091017869479904, 3.5043545530610594, 1.7469050869996816, 0.27629788253621479},
     -18.441559932058901},                                                                              // k=1054
    {24, 2, {-29.374959365636979, -12.309192201539119, -44.054881355911938}, 21731895.747123357},       // k=706
    {24, 5, {0.080430009282935061, 0.027208833865365444, 0.16435769277051079}, -100.79829762363747},    // k=709
};

}  // namespace

TEST_CASE("BBOB instances reproduce values computed by COCO", "[bbob]") {
    std::vector<bool> covered(25, false);
    for (const auto& ref : coco_values) {
        const auto d = static_cast<std::int64_t>(ref.x.size());
        INFO("f" << ref.function << " instance " << ref.instance << " D=" << d);
        const auto p = bbob(ref.function, d, ref.instance);
        const Vector x = Eigen::Map<const Vector>(ref.x.data(), d);
        REQUIRE(at(*p, x) == Approx(ref.f).epsilon(1e-10).margin(1e-9));
        covered[static_cast<std::size_t>(ref.function)] = true;
    }
    for (int f = 1; f <= 24; ++f) REQUIRE(covered[static_cast<std::size_t>(f)]);
}

TEST_CASE("BBOB f_opt of instance 1 is COCO's", "[bbob]") {
    // The f_opt of bbob_fXXX_i01 in COCO's data sets, clipped to +-1000 on f15 and f22.
    const std::array<double, 24> published{79.48,  -209.88, -462.09, -462.09, -9.21,   35.90,  92.94,   149.15,
                                           123.83, -54.94,  76.27,   -621.11, 29.97,   -52.35, 1000.00, 71.35,
                                           -16.94, -16.94,  -102.55, -546.50, 40.78,   -1000.00, 6.87,  102.61};
    for (int f = 1; f <= 24; ++f) {
        INFO("f" << f);
        for (std::int64_t d : {2, 10, 40}) REQUIRE(*bbob(f, d)->truth().optimum_value == published[f - 1]);
    }
    REQUIRE(*bbob(3, 10)->truth().optimum_value == *bbob(4, 10)->truth().optimum_value);   // f4 borrows f3's seed
    REQUIRE(*bbob(17, 10)->truth().optimum_value == *bbob(18, 10)->truth().optimum_value);  // f18 borrows f17's
    for (int f = 1; f <= 24; ++f) {
        const double fopt = *bbob(f, 5)->truth().optimum_value;
        REQUIRE(fopt >= -1000.0);
        REQUIRE(fopt <= 1000.0);
        REQUIRE(std::round(fopt * 100) == Approx(fopt * 100).margin(1e-9));  // rounded to 0.01
    }
}

TEST_CASE("every BBOB function attains f_opt at its optimum and not at the origin", "[bbob]") {
    for (std::int64_t d : {2, 3, 5, 10, 20, 40}) {
        for (std::int64_t instance : {1, 2, 7}) {
            for (int f = 1; f <= 24; ++f) {
                INFO("f" << f << " D=" << d << " instance " << instance);
                const auto p = bbob(f, d, instance);
                REQUIRE(p->dimension() == d);
                REQUIRE((p->bounds().lower.array() == -5.0).all());
                REQUIRE((p->bounds().upper.array() == 5.0).all());
                const double fopt = *p->truth().optimum_value;
                REQUIRE(at(*p, Vector::Zero(d)) > fopt + 1e-6);
                if (!p->truth().true_parameters) {
                    REQUIRE((f == 7 || f == 16 || f == 23));
                    continue;
                }
                const Vector& best = *p->truth().true_parameters;
                REQUIRE(best.size() == d);
                REQUIRE(best.cwiseAbs().maxCoeff() <= 5.0);
                REQUIRE(at(*p, best) == Approx(fopt).margin(1e-10));
            }
        }
    }
}

TEST_CASE("BBOB optima are minima: random points and small perturbations never go below f_opt", "[bbob]") {
    Rng rng(2024);
    for (int f = 1; f <= 24; ++f) {
        const auto p = bbob(f, 5, 3);
        INFO("f" << f);
        const double fopt = *p->truth().optimum_value;
        Matrix x(5, 400);
        fill_uniform(x, p->bounds(), rng);
        if (p->truth().true_parameters)  // half of the points within 1e-3 of the optimum
            for (Eigen::Index j = 0; j < 200; ++j)
                for (Eigen::Index i = 0; i < 5; ++i)
                    x(i, j) = std::clamp((*p->truth().true_parameters)[i] + 1e-3 * (2 * rng.uniform() - 1), -5.0, 5.0);
        Vector fx(400);
        p->evaluate(x, fx);
        REQUIRE(fx.minCoeff() >= fopt - 1e-12);
    }
}

TEST_CASE("the optima that are not a plain shift sit where the definitions put them", "[bbob]") {
    // f5: the corner 5 * sign(x_opt) on the boundary.
    const Vector slope = *bbob(5, 10)->truth().true_parameters;
    REQUIRE((slope.cwiseAbs().array() == 5.0).all());
    // f24: x_opt = mu0/2 * 1+- = +-1.25; f20: |x_opt| = 4.2096874637/2 up to 1e-9.
    REQUIRE((bbob(24, 10)->truth().true_parameters->cwiseAbs().array() == 1.25).all());
    const auto schwefel = bbob(20, 10);
    REQUIRE(((schwefel->truth().true_parameters->cwiseAbs().array() - 4.2096874637 / 2).abs() < 1e-9).all());
    // f9 and f19: z = max(1, sqrt(D)/8) R x + 1/2 equals 1 at the optimum, so |x_opt| = 1/(2 max(1, sqrt(D)/8)).
    for (int f : {9, 19}) {
        for (std::int64_t d : {10, 40}) {
            const double factor = std::max(1.0, std::sqrt(static_cast<double>(d)) / 8.0);
            REQUIRE(bbob(f, d)->truth().true_parameters->norm() ==
                    Approx(std::sqrt(static_cast<double>(d)) / (2 * factor)).epsilon(1e-12));
        }
    }
    // f8: x_opt is 0.75 of the grid x_opt, so it lies on a 0.0006 grid in [-3, 3].
    const Vector rosen = *bbob(8, 10)->truth().true_parameters;
    REQUIRE(rosen.cwiseAbs().maxCoeff() <= 3.0);
    for (Eigen::Index i = 0; i < rosen.size(); ++i)
        REQUIRE(std::abs(rosen[i] / 0.0006 - std::round(rosen[i] / 0.0006)) < 1e-6);
}

TEST_CASE("BBOB instances are reproducible and differ by instance number", "[bbob]") {
    Rng rng(8);
    Matrix x(10, 64);
    for (int f = 1; f <= 24; ++f) {
        INFO("f" << f);
        const auto a = bbob(f, 10, 1), again = bbob(f, 10, 1), other = bbob(f, 10, 2);
        fill_uniform(x, a->bounds(), rng);
        Vector fa(64), fagain(64), fother(64);
        a->evaluate(x, fa);
        again->evaluate(x, fagain);
        other->evaluate(x, fother);
        REQUIRE(fa == fagain);
        REQUIRE(fa != fother);
        if (f != 4 && f != 18) REQUIRE(*a->truth().optimum_value != *other->truth().optimum_value);
        if (a->truth().true_parameters)
            REQUIRE(*a->truth().true_parameters != *other->truth().true_parameters);
    }
}

TEST_CASE("BBOB functions evaluate a population exactly as one column at a time", "[bbob]") {
    Rng rng(9);
    for (int f = 1; f <= 24; ++f) {
        INFO("f" << f);
        const auto p = bbob(f, 7, 3);
        Matrix x(7, 33);
        fill_uniform(x, p->bounds(), rng);
        Vector batch(33);
        p->evaluate(x, batch);
        for (Eigen::Index j = 0; j < x.cols(); ++j) REQUIRE(batch[j] == at(*p, x.col(j)));
    }
}

TEST_CASE("BBOB parameters are checked", "[bbob]") {
    REQUIRE(make_problem("bbob_f1")->dimension() == 10);
    REQUIRE_THROWS_AS(bbob(1, 1), ParameterError);
    REQUIRE_THROWS_AS(bbob(1, 10, 0), ParameterError);
    REQUIRE_THROWS_AS(make_problem("bbob_f25"), UnknownPlugin);
}

TEST_CASE("random search never beats a BBOB function's f_opt", "[bbob]") {
    for (int f = 1; f <= 24; ++f) {
        INFO("f" << f);
        const auto p = bbob(f, 2, 1);  // in 2-D random search gets close, so the bound is tested hard
        auto search = make_optimizer("random_search", {{"batch", std::int64_t{500}}});
        const auto record = run_trial(*search, *p, {Budget{0, 20000}, 31, false});
        REQUIRE(record.ok);
        REQUIRE(record.best_fitness >= *p->truth().optimum_value - 1e-12);
        REQUIRE(record.best_fitness < at(*p, Vector::Zero(2)));
    }
}

// Registers the Snake Optimizer family from one table: SOA, ISOA and every combination of ISOA's
// three strategies in between. Every name builds the same class; a name only sets the defaults of
// the booleans `tent_init`, `cuckoo` and of the two thresholds, so `soa` with
// tent_init=true, cuckoo=true, food_threshold=0.22, temperature_threshold=0.8 is `isoa`.
#include "framework/registry.hpp"
#include "optimizers/snake/snake_optimizer.hpp"

namespace mhb {
namespace {

struct SnakeVariant {
    const char* name;
    const char* summary;
    bool tent_init;
    bool thresholds;
    bool cuckoo;
};

constexpr SnakeVariant kVariants[] = {
    {"soa", "Snake Optimizer (Hashim & Hussien 2022), as the authors' SO.m", false, false, false},
    {"soa+tent", "SO + Tent-chaos/quasi-opposition initialisation (ISOA strategy 1 only)", true, false, false},
    {"soa+thresholds", "SO with ISOA's thresholds 0.22/0.8 (ISOA strategy 2 only)", false, true, false},
    {"soa+cuckoo", "SO + Cauchy-mutated cuckoo search pass (ISOA strategy 3 only)", false, false, true},
    {"soa+tent+thresholds", "SO + ISOA strategies 1 and 2", true, true, false},
    {"soa+tent+cuckoo", "SO + ISOA strategies 1 and 3", true, false, true},
    {"soa+thresholds+cuckoo", "SO + ISOA strategies 2 and 3", false, true, true},
    {"isoa", "Improved Snake Optimizer (He et al. 2024): SO + all three strategies", true, true, true},
};

std::vector<ParameterSpec> snake_parameters(const SnakeVariant& v) {
    return {
        ParameterSpec::integer("population", 30, 2, 1'000'000,
                               "snakes N, even: first half males, second half females (>= 6 with the cuckoo pass)"),
        ParameterSpec::choice("fitness_ratio", "faithful", {"faithful", "shifted"},
                              "ratios exp(-f_other/(f_self+eps)) on raw fitness (SO.m; assumes f >= 0) or on "
                              "fitness minus the population minimum"),
        ParameterSpec::real("food_threshold", v.thresholds ? 0.22 : 0.25, 0.0, 1.0,
                            "T_h1 (eq. 7): exploration while Q < T_h1; SO 0.25, ISOA 0.22"),
        ParameterSpec::real("temperature_threshold", v.thresholds ? 0.8 : 0.6, 0.0, 1.0,
                            "T_h2 (eq. 9): hot exploitation while Temp > T_h2; SO 0.6, ISOA 0.8"),
        ParameterSpec::boolean("tent_init", v.tent_init,
                               "Tent-chaos + quasi-opposition initialisation (eq. 13-16), keep best N of the union"),
        ParameterSpec::real("tent_epsilon", 0.6, 0.01, 0.99, "Tent map control parameter epsilon (eq. 13)"),
        ParameterSpec::real("jumping_rate", 0.3, 0.0, 1.0,
                            "probability that an individual adds a quasi-opposite point (p_i of eq. 16)"),
        ParameterSpec::boolean("cuckoo", v.cuckoo,
                               "Cauchy-mutated cuckoo search pass (eq. 17-25) on each sex after SO's update"),
        ParameterSpec::real("cauchy_mu0", 0.5, -10.0, 10.0, "initial location mu_0 of the Cauchy step factor (eq. 22)"),
        ParameterSpec::real("mu_weight", 0.1, 0.0, 1.0,
                            "w in mu <- w mu + (1-w) L_s (eq. 23): paper 0.1, JADE 0.9"),
        ParameterSpec::real("discovery_probability", 0.25, 0.0, 1.0,
                            "p_a (eq. 19): each coordinate moves in the discovery pass with probability 1 - p_a"),
        ParameterSpec::choice("cauchy_alpha", "jade", {"jade", "raw"},
                              "step factor alpha: jade = redraw while <= 0, cut at 1 (alpha in (0,1]); raw = as drawn"),
        ParameterSpec::choice("cuckoo_leader", "own_sex", {"own_sex", "food"},
                              "best position of eq. (24) for a sex's cuckoo pass: that sex's best or the global best"),
    };
}

std::unique_ptr<Optimizer> make_snake(const ParameterSet& p) {
    SnakeSettings s;
    s.population = static_cast<Eigen::Index>(p.integer("population"));
    s.fitness_ratio = parse_fitness_ratio(p.text("fitness_ratio"));
    s.schedule.food_threshold = p.real("food_threshold");
    s.schedule.temperature_threshold = p.real("temperature_threshold");
    if (p.boolean("tent_init")) s.tent_init = TentQuasiOppositionSettings{p.real("tent_epsilon"), p.real("jumping_rate")};
    if (p.boolean("cuckoo"))
        s.cuckoo = CauchyCuckooSettings{p.real("cauchy_mu0"), p.real("mu_weight"), p.real("discovery_probability"),
                                        parse_cauchy_alpha_rule(p.text("cauchy_alpha"))};
    s.cuckoo_leader = parse_cuckoo_leader(p.text("cuckoo_leader"));
    return std::make_unique<SnakeOptimizer>(s);
}

const bool registered = [] {
    bool all = true;
    for (const auto& v : kVariants) all &= register_optimizer({v.name, v.summary, snake_parameters(v), make_snake});
    return all;
}();

}  // namespace
}  // namespace mhb

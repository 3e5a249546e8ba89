// jSO: J. Brest, M. S. Maučec, B. Bošković, "Single objective real-parameter optimization: algorithm
// jSO", IEEE CEC 2017, 1311-1318. L-SHADE (optimizers/lshade.hpp) with iL-SHADE's and jSO's changes:
// other initial memories and a fixed last slot, the weighted mutation current-to-pBest-w/1, schedules
// of CR, F and p over the budget, and memory updates averaged with the old entry. docs/algorithms.md.
#include "optimizers/jso.hpp"

#include <algorithm>
#include <cmath>

#include "framework/registry.hpp"

namespace mhb::shade {

Jso::Jso(const ParameterSet& p) : Lshade(jso_settings(p)) {}

Settings Jso::jso_settings(const ParameterSet& p) {
    Settings s = settings_from(p);
    s.initial_memory_f = 0.3;
    s.initial_memory_cr = 0.8;
    return s;
}

Eigen::Index Jso::initial_population(int dimension) const {
    const double d = dimension;
    return static_cast<Eigen::Index>(std::round(25.0 * std::log(d) * std::sqrt(d)));
}

// The last of the H slots always gives 0.9 and 0.9.
std::pair<double, double> Jso::memory_means(int slot) const {
    if (slot == settings().memory_size - 1) return {0.9, 0.9};
    return Lshade::memory_means(slot);
}

double Jso::adjusted_cr(double cr, double used) const {
    if (used < 0.25) return std::max(cr, 0.7);
    if (used < 0.5) return std::max(cr, 0.6);
    return cr;
}

double Jso::adjusted_f(double f, double used) const { return used < 0.6 ? std::min(f, 0.7) : f; }

// F_w of current-to-pBest-w/1.
double Jso::pbest_factor(double f, double used) const {
    if (used < 0.2) return 0.7 * f;
    if (used < 0.4) return 0.8 * f;
    return 1.2 * f;
}

// p falls linearly from p_max to p_max / 2.
double Jso::p_best_rate(double used) const { return settings().p_best * (1.0 - 0.5 * used); }

bool Jso::pbest_may_be_target(double used) const { return used >= 0.5; }

// Each new entry is the mean of the old one and the generation's Lehmer mean; a terminal CR mean
// (-1) is averaged in as the authors' code does, so the slot is terminal while it stays below 0 and
// leaves ⊥ as later means pull it up. sticky_terminal_cr keeps a slot at ⊥ once it is below 0
// instead, L-SHADE's rule carried over to jSO's reading of ⊥.
std::pair<double, double> Jso::updated_memory(double old_f, double old_cr, double f_mean, double cr_mean) const {
    const double f = (f_mean + old_f) / 2.0;
    if (settings().sticky_terminal_cr && old_cr < 0.0) return {f, terminal_cr};
    return {f, (cr_mean + old_cr) / 2.0};
}

namespace {

const bool registered = register_optimizer({
    "jso",
    "jSO: L-SHADE with weighted mutation and parameter schedules (Brest, Maucec & Boskovic, CEC 2017)",
    {
        ParameterSpec::integer("population", 0, 0, 1'000'000,
                               "initial population N_init; 0 = round(25 ln(D) sqrt(D))"),
        ParameterSpec::real("archive_rate", 1.0, 0.0, 100.0, "archive size |A| = round(archive_rate x N)"),
        ParameterSpec::integer("memory_size", 5, 2, 1000, "H, entries of the memory; the last is fixed at 0.9, 0.9"),
        ParameterSpec::real("p_best", 0.25, 0.0, 1.0, "p_max: p falls linearly from p_max to p_max/2 over the budget"),
        archive_entry_parameter(),
        ParameterSpec::boolean("sticky_terminal_cr", false,
                               "true: a CR memory slot below 0 (terminal) stays terminal; false: it is averaged with "
                               "later means and may leave it (the authors' code)"),
    },
    [](const ParameterSet& p) { return std::make_unique<Jso>(p); },
});

}  // namespace
}  // namespace mhb::shade

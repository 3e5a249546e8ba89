#pragma once
// The Snake Optimizer's phase schedule: food quantity Q (seed paper eq. 7) and temperature (eq. 9)
// as functions of the run fraction t/T, compared with two thresholds. ISOA's second strategy
// (section 3.1.2) is nothing but other threshold values: 0.22 and 0.8 instead of 0.25 and 0.6.
#include <cmath>

namespace mhb {

enum class SnakePhase { Exploration, Hot, Fight, Mating };

struct SnakePhaseSchedule {
    double food_threshold = 0.25;         // T_h1: exploration while Q < T_h1
    double temperature_threshold = 0.6;   // T_h2: "hot" exploitation while Temp > T_h2

    // Eq. (7): Q = 0.5 exp(t/T - 1), SO.m's C1 exp((t - T)/T) with C1 = 0.5; capped at 1 as SO.m does.
    static double food_quantity(double fraction) { return std::fmin(0.5 * std::exp(fraction - 1.0), 1.0); }
    // Eq. (9): Temp = exp(-t/T).
    static double temperature(double fraction) { return std::exp(-fraction); }

    bool exploring(double fraction) const { return food_quantity(fraction) < food_threshold; }
    bool hot(double fraction) const { return temperature(fraction) > temperature_threshold; }
};

}  // namespace mhb

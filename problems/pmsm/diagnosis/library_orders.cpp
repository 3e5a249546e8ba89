#include "problems/pmsm/diagnosis/library_orders.hpp"

#include <cmath>
#include <cstdlib>

#include "problems/pmsm/diagnosis/verdict.hpp"
#include "problems/pmsm/effects/effect.hpp"

namespace mhb::pmsm {

HarmonicOrders orders_laws_make(const ModelSpec& set) {
    HarmonicOrders made{};
    const auto mark = [&](int order) {
        if (order >= 1 && order <= harmonic_orders) made[static_cast<std::size_t>(order)] = true;
    };
    for (const auto* entry : EffectRegistry::instance().entries())
        for (const int order : make_effect(entry->name)->angle_orders()) mark(order);
    std::vector<std::vector<int>> fitted;
    for (const auto& term : set.effects) fitted.push_back(make_effect(term.name)->angle_orders());
    for (std::size_t a = 0; a < fitted.size(); ++a)
        for (std::size_t b = a + 1; b < fitted.size(); ++b)
            for (const int x : fitted[a])
                for (const int y : fitted[b]) {
                    mark(x + y);
                    mark(std::abs(x - y));
                }
    return made;
}

std::vector<Harmonic> harmonics_outside_library(const LackOfFit& left, const ModelSpec& set, const NoiseEstimate& noise) {
    const double resolution = std::sqrt(noise.sigma.squaredNorm() / 2.0);
    std::vector<Harmonic> out;
    HarmonicOrders made{};
    bool known = false;
    for (const auto& h : left.harmonics) {
        if (!h.significant || 0.5 * h.amplitude.norm() < evidence::relevant_voltage * resolution) continue;
        if (!known) {
            made = orders_laws_make(set);
            known = true;
        }
        if (!made[static_cast<std::size_t>(h.order)]) out.push_back(h);
    }
    return out;
}

}  // namespace mhb::pmsm

#pragma once
// Whether a harmonic of the electrical angle left in a residual is one that some library law makes
// (Effect::angle_orders: at another size, or by the law's own error on a rippling current) or one
// that no library law makes at any size, the signature of physics outside the library
// (docs/diagnosis.md, section 3, "A harmonic no library law makes").
#include <array>
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/lack_of_fit.hpp"

namespace mhb::pmsm {

// Per order 1..harmonic_orders (index 0 unused): whether a law makes it. Every registered effect's
// own orders, and for the laws of `set` fitted together, the sums and differences of two different
// laws' orders (one law's error on the ripple another makes).
using HarmonicOrders = std::array<bool, harmonic_orders + 1>;
HarmonicOrders orders_laws_make(const ModelSpec& set);

// The harmonics of `left` (a step's lack of fit, `set` its model) that are significant, change the
// voltage by a relevant amount (evidence::relevant_voltage of the noise's rms: the rms over both
// axes of a harmonic of amplitudes a_d, a_q is sqrt((a_d^2 + a_q^2) / 4)) and lie at an order no
// law makes (orders_laws_make).
std::vector<Harmonic> harmonics_outside_library(const LackOfFit& left, const ModelSpec& set, const NoiseEstimate& noise);

}  // namespace mhb::pmsm

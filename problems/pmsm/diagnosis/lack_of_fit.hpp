#pragma once
// Lack of fit: structure in a residual beyond the noise. The segment means (each one's variance
// under noise alone is the long-run variance over its rows) and, when the angle is logged, the
// harmonics of the electrical angle fitted jointly with them and each segment's trend in time; when
// the shaft's angle is known, the harmonics at mechanical orders too.
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/diagnosis/shaft_angle.hpp"

namespace mhb::pmsm {

inline constexpr int harmonic_orders = 12;  // of the electrical angle, tested in lack_of_fit
// Of the shaft angle: 1 to this, less the multiples of the pole pairs (electrical orders). Once and
// twice per turn are eccentricity's, a bent shaft's and a load's; 3 and 4 a coupling's or a gear's.
inline constexpr int mechanical_orders = 4;

// P(chi^2_dof > statistic); 1 without degrees of freedom.
double chi_squared_survival(double statistic, double dof);

// Harmonics 1 to harmonic_orders of the electrical angle in `residual` (both axes stacked), fitted
// jointly with one mean and one linear trend in time per segment; each with its amplitude per axis,
// the standard error of an amplitude component under noise alone and the p-value of the more
// significant axis. Needs theta_e. The trends because a segment that turns the rotor through less
// than a period of an order makes that order's cos and sin smooth in time there, and a drift within
// the segment (heating, a settling loop) would otherwise pass for it; where they are collinear the
// order's standard error widens instead.
std::vector<Harmonic> angle_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise);

// Harmonics at mechanical orders k = 1..mechanical_orders, k not a multiple of the pole pairs, of
// `shaft` in `residual`, each carried only by the segments whose shaft turns through a whole period
// of it (k x travel >= 2 pi): over less, a drift within a segment would pass for it. Fitted jointly
// with one mean per segment, the electrical harmonics (theta_e logged) and each other; with the
// logged angle two coefficients per order, the columns turned in sign with the direction of
// rotation (an EMF or an angle error of the shaft changes sign with the speed), with the integrated
// one two per order and segment (its zero differs per segment). The Wald statistic of each order's coefficients against chi-square on
// their count. `note` says which orders were tested, or why none.
struct MechanicalTest {
    std::vector<MechanicalHarmonic> harmonics;
    std::string note;
};
MechanicalTest mechanical_harmonics(const Measurement& data, const Eigen::VectorXd& residual, const NoiseEstimate& noise, const ShaftAngle& shaft);

// The segment means of `fit`'s residual on `axis` (0: u_d, 1: u_q) in words: how large, and the
// operating condition they follow when one does (|r| >= 0.7).
std::string segment_means_signature(const Measurement& data, const ModelFit& fit, int axis);

// `residual` is the fit's (residual_of). Structure is significant at p < evidence::significance, for
// the harmonics after Bonferroni over their tests: two (the axes) per electrical and per mechanical
// order tested. The mechanical orders only with `shaft` given (its source set).
LackOfFit lack_of_fit(const Measurement& data, const ModelFit& fit, const Eigen::VectorXd& residual, const NoiseEstimate& noise,
                      const ShaftAngle& shaft = {});

}  // namespace mhb::pmsm

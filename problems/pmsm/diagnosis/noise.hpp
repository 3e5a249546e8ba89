#pragma once
// The noise a diagnosis measures its evidence in: the long-run variance of each axis' residual
// within segments, and the likelihood ratio in units of it.
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// The residual of `fit` with each segment's mean removed: its standard deviation per axis, and the
// long-run standard deviation of its mean (AR(1)-prewhitened Newey-West, at least sigma). The
// dispersion is left at 1.
NoiseEstimate estimate_noise(const Measurement& data, const ModelFit& fit);

// The electrical angle of each row, as window_noise bins it: the logged theta_e, else omega_e
// integrated over t; none without either.
class WindowAngles {
public:
    explicit WindowAngles(const Measurement& data);
    bool available() const;
    double operator[](Eigen::Index row) const;
    std::string text() const;  // where the angle comes from; empty when there is none

private:
    const Measurement& data_;
    bool logged_;
    Eigen::VectorXd integrated_;
};

// What a steady window's residual holds besides noise, removed: its least-squares quadratic in time
// (times scaled to [-1, 1], row numbers without t) and its mean in each of up to window_noise_bins
// bins of the electrical angle (window_noise_rows_per_bin rows a bin on average).
class WindowProjection {
public:
    WindowProjection(const Measurement& data, const WindowAngles& angles, Eigen::Index first, Eigen::Index rows);
    Eigen::Index first() const { return first_; }
    int bins() const { return bins_; }
    // Whether the projection leaves the noise most of the window's rows (and the window has 8).
    bool leaves_noise() const;
    // Removes both from `r` (the window's rows of one axis); returns the parameters spent (3 and the
    // bins used).
    int remove(Eigen::Ref<Eigen::VectorXd> r);

private:
    Eigen::Index first_;
    int bins_;
    Eigen::VectorXd x_;
    std::vector<int> bin_;
    std::vector<double> bin_sum_;
    std::vector<int> bin_rows_;
    Eigen::LDLT<Eigen::Matrix3d> trend_;
};

// The noise measured from the data, not from the residual's level: within each segment (the whole
// log without one), per axis, the residual of `fit` less its least-squares
// quadratic in time and its mean in each of up to window_noise_bins bins of the electrical angle
// (the logged theta_e, else omega_e integrated over t), its mean square divided by the rows less
// the parameters spent. The residual, not the voltage alone: the current sensors' noise enters the
// model through R i and omega L i as it enters the residual (on the seed's servo, R = 46 ohm times
// 1 mA is more than the voltage's own noise). What a model misses within a steady window is slow
// (a drift, a settling tail: the trend) or locked to the angle (the current ripple of dead time,
// flux harmonics and the L di/dt the steady model lacks: the bins); the closed loop's noise is
// neither (its correlation dies within a few samples). First differences, used before, kept the
// ripple and needed a first-order model of the noise's correlation that the loop's noise does not
// follow (15 % high on the 5 kW machine's clean raw logs). Also the lag-one correlation of what is
// left, in [0, 0.9]. Each is the median over the segments weighted by their degrees of freedom.
WindowNoise window_noise(const Measurement& data, const ModelFit& fit);
// The same on a residual of `data` (2n rows, u_d then u_q).
WindowNoise window_noise(const Measurement& data, const Eigen::VectorXd& residual);

// How window_noise measured `noise`, in words.
std::string window_noise_method(const WindowNoise& noise);

// The angle bins of window_noise: at most this many per window, and at least this many rows in each
// on average (a window of m rows gets min(256, m / 8)), so that each bin's mean spends no more than
// an eighth of the rows' noise. 256 bins resolve the dead time's steps to 1.4 electrical degrees.
inline constexpr int window_noise_bins = 256;
inline constexpr int window_noise_rows_per_bin = 8;
// A segment's variance is known to about 1 % from this many rows (sqrt(2 / dof)); a longer one is
// measured on its middle rows, so that the search's rounds on a million-row log (each measures the
// noise on its best fit) pay a fixed cost: 1.6 % of the diagnosis's CPU when every row was used.
inline constexpr Eigen::Index window_noise_max_rows = 16384;

// When the residual's standard deviation within segments exceeds the window noise by more than
// this, the residual holds structure within segments (a trend, a ripple locked to the angle) and the
// evidence is measured in the window noise. Below it, the residual's own estimate is kept: its
// Newey-West long-run variance measures the noise's correlation better than one lag does.
inline constexpr double residual_structure_ratio = 1.5;

// Sum over axes of (RSS_model - RSS_candidate) / long-run variance, divided by the dispersion.
double likelihood_ratio(const ModelFit& model, const ModelFit& candidate, const NoiseEstimate& noise);

// The noise measured on the best-fitting of `fits` whose base parameters are all positive (the first
// of equals; the first fit when none is), with the overdispersion
// of its segment means: when even the best model tried leaves segment means that the noise cannot
// explain, every likelihood ratio is divided by that excess (Q / dof), as a quasi-likelihood does.
// `window` is window_noise on the model diagnosed; the noise of the data is, per axis, the lower of
// it and window_noise on the best fit. Each can only hold more than the noise: the model diagnosed
// what it misses that short segments' bins cannot resolve (the tutorial's 150-row segments: 18 bins
// across dead time's steps, u_d 0.057 V on base against 0.043 V on the best fit), the best fit what
// an effect's law of the measured current passes of the sensors' noise (dead time's step at each
// zero crossing: on a 5 kW raw log, seed 1, u_d 0.62 V on the best fit, 0.58 V on base, 0.52 V
// simulated).
NoiseEstimate noise_of_best(const Measurement& data, const std::vector<const ModelFit*>& fits, const WindowNoise& window);

}  // namespace mhb::pmsm

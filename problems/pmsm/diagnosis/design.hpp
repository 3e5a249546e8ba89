#pragma once
// The design: what the operating points, the logged angle and the temperature trend can tell,
// whatever the noise. An effect whose Jacobian columns lie in the span of the model's own on the
// design is absorbed without trace; hypothetical extra operating points show which experiment would
// reveal it.
#include <functional>
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// The data with each segment's currents and speed at their means and its temperatures on a straight
// line through time, so that the noise cannot make an effect look identifiable. Without segments the
// operating points are unknown: the samples themselves are the design.
Measurement design_of(const Measurement& data);

struct OperatingPoint {
    double omega = 0.0, i_d = 0.0, i_q = 0.0, temp_winding = 0.0, temp_magnet = 0.0;
};

// `design` with a hypothetical held operating point appended: one electrical period of the angle
// (72 rows) when the data log it, so angle signatures show, two rows otherwise.
Measurement with_point(const Measurement& design, const OperatingPoint& p);

// The design with a logged angle: one electrical period swept through each segment.
Measurement with_angle(const Measurement& design);

// Fraction of `column`'s norm outside the span of `others` (columns scaled first; rank-revealing
// QR). NaN for a zero column, 1 without others.
double unique_fraction(const Eigen::MatrixXd& others, const Eigen::VectorXd& column);

// Unique fraction of each free parameter of `effect` in the model `spec`+`effect`(+`rival`) on
// `design`, against the model's own free parameters (and the rival's). Effect parameters are taken
// at their declared typical (default) values, the model's at `model_values`.
std::vector<double> design_unique_fractions(const Measurement& design, const ModelSpec& spec, const Eigen::VectorXd& model_values,
                                            const std::string& effect, const std::string& rival = {});

// The largest finite fraction; NaN when none is.
double most_distinct(const std::vector<double>& fractions);

// An extra experiment, and how to add it to a design.
struct Proposal {
    Experiment experiment;
    std::function<Measurement(const Measurement&)> apply;
};

// Extra operating points around the fastest segment (another speed, the other direction, another
// d-axis current, another load, a temperature change when temperatures are logged), and logging the
// angle when it is not.
std::vector<Proposal> experiment_proposals(const Measurement& data, const std::vector<SegmentConditions>& segments);

// Experiments after which `effect` (against `rival` too, when given, and the rival against it) has
// at least evidence::clear_above of its signature to itself, the clearest first; "all of these
// together" when no single one does but all do.
std::vector<Experiment> revealing_experiments(const Measurement& design, const std::vector<Proposal>& proposals, const ModelSpec& spec,
                                              const Eigen::VectorXd& model_values, const std::string& effect,
                                              const std::string& rival = {});

}  // namespace mhb::pmsm

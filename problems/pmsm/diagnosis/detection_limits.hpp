#pragma once
// What a log cannot show: for each library effect left out of a model, the smallest size of each of
// its size parameters (Effect::is_size) that this log's design and noise would reveal. Below it an
// effect may be present and still not be found; "not in the library" is kept for structure that no
// library effect of any size produces.
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// `design`: design_of the rows searched (search_design), standing for `rows` logged rows; `model`:
// the fit the effects would be added to; `library`: the effects to state limits for (those of the
// model are skipped). A size at its limit moves the likelihood ratio by what the search needs to add
// an effect with that many parameters (evidence::supported_bic) and the modelled voltage by
// evidence::relevant_voltage of the noise, after the model's own parameters have absorbed what they
// can of it (the Fisher information of the size with the others profiled out): at the limit, about
// half of such logs would show the effect where the evidence sets it (DetectionLimit::
// set_by_relevant_size says which sets it). Effect shapes at their declared typical values.
std::vector<DetectionLimit> detection_limits(const Measurement& design, Eigen::Index rows, const ModelFit& model,
                                             const std::vector<std::string>& library, const NoiseEstimate& noise);

}  // namespace mhb::pmsm

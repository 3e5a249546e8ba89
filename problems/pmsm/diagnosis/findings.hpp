#pragma once
// The findings of a diagnosis in words: plain statements, most important first.
#include <string>
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

// The statements about a finished diagnosis `d` (everything but its findings filled in):
// `left_by_last_step` is the lack of fit of the search's last step (d.lack_of_fit when the path has
// one step), `floor_tolerance` the option that step's remaining structure was judged by.
std::vector<std::string> findings_of(const Diagnosis& d, const LackOfFit& left_by_last_step, double floor_tolerance);

}  // namespace mhb::pmsm

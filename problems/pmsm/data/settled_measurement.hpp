#pragma once
// The measurement as `mhbench fit` and `diagnose` use it: read, then the settling after each segment
// start dropped.
#include <filesystem>

#include "problems/pmsm/data/measurement.hpp"

namespace mhb::pmsm {

// Reads a measurement and drops the first `settle` seconds after each segment start; InputError when
// fewer than 10 samples remain.
Measurement read_settled_measurement(const std::filesystem::path& path, double settle, const ColumnMap& map = {});

}  // namespace mhb::pmsm

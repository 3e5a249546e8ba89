#pragma once
// The measurement's segments (operating points) as row ranges, and each one's conditions.
#include <vector>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

struct RowRange {
    Eigen::Index first = 0, rows = 0;
};

// The runs of rows with one segment label, in order; one range of all rows without a segment column.
std::vector<RowRange> segment_ranges(const Measurement& m);

// Each segment's mean operating conditions and residuals: `model`'s, and `before`'s (the base
// model's) when given, else `model`'s again. Apparent values and standard errors are left empty.
std::vector<SegmentConditions> segment_conditions(const Measurement& data, const ModelFit& model, const ModelFit* before);

}  // namespace mhb::pmsm

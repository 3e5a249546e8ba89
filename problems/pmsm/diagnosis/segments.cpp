#include "problems/pmsm/diagnosis/segments.hpp"

namespace mhb::pmsm {

std::vector<RowRange> segment_ranges(const Measurement& m) {
    std::vector<RowRange> out;
    Eigen::Index begin = 0;
    for (Eigen::Index k = 1; k <= m.size(); ++k)
        if (k == m.size() || (m.has_segments() && m.segment[k] != m.segment[k - 1])) {
            out.push_back({begin, k - begin});
            begin = k;
        }
    return out;
}

std::vector<SegmentConditions> segment_conditions(const Measurement& data, const ModelFit& model, const ModelFit* before) {
    std::vector<SegmentConditions> out;
    for (std::size_t s = 0; s < model.segments.size(); ++s) {
        const auto& seg = model.segments[s];
        SegmentConditions c;
        c.label = seg.label;
        c.first = seg.first;
        c.rows = seg.rows;
        auto mean = [&](const Eigen::VectorXd& v) { return v.segment(seg.first, seg.rows).mean(); };
        c.omega = mean(data.omega_e);
        c.i_d = mean(data.i_d);
        c.i_q = mean(data.i_q);
        if (data.temp_winding) c.temp_winding = mean(*data.temp_winding);
        if (data.temp_magnet) c.temp_magnet = mean(*data.temp_magnet);
        if (data.t) c.time = mean(*data.t);
        c.model = seg;
        c.before = before ? before->segments[s] : seg;
        out.push_back(c);
    }
    return out;
}

}  // namespace mhb::pmsm

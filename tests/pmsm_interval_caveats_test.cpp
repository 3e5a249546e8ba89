// What the diagnosis states beside the recommended model's intervals, per base parameter
// (problems/pmsm/diagnosis/interval_caveats.hpp); a law held to fewer terms is checked against the
// plant's values in tests/pmsm_effect_set_search_test.cpp.
#include <catch2/catch.hpp>

#include "problems/pmsm/diagnosis/interval_caveats.hpp"

using namespace mhb::pmsm;

namespace {

// A diagnosis whose search stopped at `model`, recommended, with the device servo's base values.
Diagnosis recommending(const std::string& model) {
    Diagnosis d;
    PathStep step;
    step.fit.spec = parse_model_spec(model);
    step.fit.values = Eigen::VectorXd::Zero(6);  // the effects' values are not read: only the laws' statements
    step.fit.values.head<4>() << 46.0, 0.02025, 0.02025, 0.04375;
    d.path.push_back(step);
    d.recommended = step.fit.spec;
    return d;
}

}  // namespace

TEST_CASE("a stated bias marks every base parameter's interval, and a model without one marks none", "[pmsm][diagnosis]") {
    Diagnosis d = recommending("base+deadtime");
    d.interval_caveats = interval_caveats(Measurement{}, d, FitOptions{});
    REQUIRE(d.interval_caveats.size() == 1);
    // The dead-time law's pulse shift, R_s t_d / (2 L) = 0.114 % per microsecond here.
    CHECK(d.interval_caveats.front().reason.find("up to 0.11 % per microsecond") != std::string::npos);
    for (std::size_t j = 0; j < 4; ++j) {
        CHECK(d.interval_caveats.front().base[j]);
        CHECK(d.recommended_interval_marked(j));
    }

    Diagnosis plain = recommending("base+encoder_offset");
    plain.interval_caveats = interval_caveats(Measurement{}, plain, FitOptions{});
    CHECK(plain.interval_caveats.empty());
    for (std::size_t j = 0; j < 4; ++j) CHECK_FALSE(plain.recommended_interval_marked(j));
    // Intervals that are not valid at all are marked whatever the caveats.
    plain.incomplete = true;
    for (std::size_t j = 0; j < 4; ++j) CHECK(plain.recommended_interval_marked(j));
}

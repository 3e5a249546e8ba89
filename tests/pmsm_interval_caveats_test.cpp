// What the diagnosis states beside the recommended model's intervals, per base parameter
// (problems/pmsm/diagnosis/interval_caveats.hpp); a law held to fewer terms is checked against the
// plant's values in tests/pmsm_effect_set_search_test.cpp.
#include <catch2/catch.hpp>

#include <algorithm>

#include "problems/pmsm/diagnosis/interval_caveats.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"

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

namespace {

// A diagnosis that recommends the model it diagnosed, `spec` fitted to `data`.
Diagnosis recommending_fit_of(const Measurement& data, const std::string& spec) {
    Diagnosis d;
    d.model = fit_model(data, parse_model_spec(spec), FitOptions{});
    d.recommended = d.model.spec;
    return d;
}

bool extrapolation_marked(const std::vector<IntervalCaveat>& caveats) {
    return std::any_of(caveats.begin(), caveats.end(), [](const IntervalCaveat& c) {
        return c.reason.find("extrapolation") != std::string::npos && c.base == std::array<bool, 4>{false, true, true, true};
    });
}

}  // namespace

TEST_CASE("zero-current values a law reaches only by extrapolation are marked: a measured saturated map, not linear iron",
          "[pmsm][diagnosis]") {
    // The Baldor map's machine is saturated at every logged current (the smallest, 3 A on q): the
    // saturation law's flux there is far off the line its L_d, L_q and psi_f draw from zero current.
    const Measurement& map = mhb::pmsm::testing::simulated("flux_map", "flux_map_diagnosis_profile.toml", {}, true);
    Diagnosis saturated = recommending_fit_of(map, "base+saturation");
    CHECK(extrapolation_marked(interval_caveats(map, saturated, FitOptions{})));
    // The Table 1 servo's linear iron: the same law fitted there stays on its line within psi_f's interval.
    const Measurement& linear = mhb::pmsm::testing::diagnosis_data({});
    Diagnosis straight = recommending_fit_of(linear, "base+saturation");
    CHECK_FALSE(extrapolation_marked(interval_caveats(linear, straight, FitOptions{})));
}

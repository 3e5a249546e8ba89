// The findings alone (problems/pmsm/diagnosis/findings.hpp): the statements written for diagnoses
// built by hand.
#include <catch2/catch.hpp>

#include <algorithm>

#include "problems/pmsm/diagnosis/findings.hpp"

using namespace mhb::pmsm;

namespace {

ModelFit fit_of(const std::string& spec, double rms, std::vector<std::pair<std::string, double>> effect_values = {}) {
    ModelFit f;
    f.spec = parse_model_spec(spec);
    f.names = {"Rs", "Ld", "Lq", "psi_f"};
    f.units = {"Ohm", "H", "H", "Vs"};
    f.values = Eigen::Vector4d(46.0, 0.02, 0.02, 0.044);
    for (const auto& [name, value] : effect_values) {
        f.names.push_back(name);
        f.units.push_back("V");
        f.values.conservativeResize(f.values.size() + 1);
        f.values[f.values.size() - 1] = value;
    }
    f.free.assign(f.names.size(), true);
    f.rms = {rms, rms, rms};
    return f;
}

PathStep step(ModelFit fit, StepKind kind = StepKind::Start, std::string effect = {}) {
    PathStep s;
    s.fit = std::move(fit);
    s.kind = kind;
    s.effect = std::move(effect);
    return s;
}

// A base model on segmented data with a temperature column, nothing found yet.
Diagnosis diagnosis_of_base() {
    Diagnosis d;
    d.columns = {"segment", "temp_winding"};
    d.model = fit_of("base", 0.2);
    d.build_up = {d.model};
    d.noise.model = "base";
    d.noise.sigma = {0.01, 0.02};
    d.mean_equations = 18;
    d.lack_of_fit.means_available = true;
    d.path = {step(d.model)};
    d.recommended = d.model.spec;
    return d;
}

bool says(const std::vector<std::string>& findings, const std::string& sentence) {
    return std::find(findings.begin(), findings.end(), sentence) != findings.end();
}

}  // namespace

TEST_CASE("a model at the noise floor: its residual against the noise, and no missing effect", "[pmsm][diagnosis][findings]") {
    const Diagnosis d = diagnosis_of_base();
    const auto f = findings_of(d, d.lack_of_fit, 0.25);
    REQUIRE(f.size() == 2);
    CHECK(f[0] == "base fits with a residual of 0.2 V rms (u_d 0.2 V, u_q 0.2 V); the noise alone is 0.01 V on u_d and 0.02 V on u_q "
                  "(measured on base).");
    CHECK(f[1] == "No missing effect: the residual is at the noise floor and no library effect earns its parameters.");
}

TEST_CASE("data that cannot tell: no segments, too few operating points, columns missing", "[pmsm][diagnosis][findings]") {
    Diagnosis d = diagnosis_of_base();
    d.columns = {};
    d.lack_of_fit.means_available = false;
    d.not_tried = {{"rs_thermal", "temp_winding"}};
    auto f = findings_of(d, d.lack_of_fit, 0.25);
    CHECK_THAT(f[1], Catch::StartsWith("The data have no segment column"));
    CHECK(says(f, "No missing effect can be seen on this data."));
    CHECK(f.back() == "rs_thermal was not tried: it needs the column temp_winding, which the data lack (log it to check this effect).");
    d.columns = {"segment"};
    d.mean_equations = 4;
    f = findings_of(d, d.lack_of_fit, 0.25);
    CHECK_THAT(f[1], Catch::StartsWith("The 2 operating points give 4 segment-mean equations for the 4 free parameters of base:"));
}

TEST_CASE("one effect found: what it is, its values and the evidence against the next best", "[pmsm][diagnosis][findings]") {
    Diagnosis d = diagnosis_of_base();
    Candidate found, next;
    found.effect = "voltage_offset";
    found.delta_bic = -120.04;
    found.verdict = Verdict::Supported;
    next.effect = "deadtime";
    next.delta_bic = -3.0;
    next.verdict = Verdict::Weak;
    d.candidates = {found, next};
    d.path.push_back(step(fit_of("base+voltage_offset", 0.05, {{"voltage_offset.u_d0", 0.3}}), StepKind::Added, "voltage_offset"));
    d.path.back().at_noise_floor = true;
    d.missing_effect_found = true;
    d.recommended_step = d.path.size() - 1;
    d.winner = "voltage_offset";
    const auto f = findings_of(d, LackOfFit{}, 0.25);
    CHECK(says(f, "Missing effect: voltage_offset (its fit: voltage_offset.u_d0 = 0.3 V). Adding it lowers the residual to 0.05 V rms; "
                  "evidence dBIC = -120.0, the next best (deadtime) -3.0."));
    CHECK_FALSE(says(f, "No missing effect: the residual is at the noise floor and no library effect earns its parameters."));
}

TEST_CASE("one effect found where the table divides its evidence by an overdispersion: the search's evidence is quoted, the table's beside it",
          "[pmsm][diagnosis][findings]") {
    // Saturating iron on the device servo: the table of single additions divides the likelihood
    // ratio by the overdispersion of the segment means (8.48) and shows +30.3; the search, which
    // does not divide, added the effect at -87.6. Quoting the +30.3 alone gave a positive dBIC as
    // the evidence for the effect found.
    Diagnosis d = diagnosis_of_base();
    d.noise.dispersion = 8.48;
    Candidate found, next;
    found.effect = "saturation";
    found.delta_bic = 30.3;
    found.verdict = Verdict::NotSupported;
    next.effect = "encoder_offset";
    next.delta_bic = 7.2;
    next.verdict = Verdict::NotSupported;
    d.candidates = {next, found};
    d.path.push_back(step(fit_of("base+saturation", 0.035, {{"saturation.q_self", 0.0062}}), StepKind::Added, "saturation"));
    d.path.back().delta_bic = -87.6;
    d.path.back().at_noise_floor = true;
    d.missing_effect_found = true;
    d.recommended_step = d.path.size() - 1;
    d.winner = "saturation";
    const auto f = findings_of(d, LackOfFit{}, 0.25);
    CHECK(std::any_of(f.begin(), f.end(), [](const std::string& s) {
        return s.find("evidence dBIC = -87.6 in the search over sets (30.3 in the table above, which divides the evidence by the overdispersion "
                      "of the segment means, 8.48); the next best there (encoder_offset) 7.2.") != std::string::npos;
    }));
}

TEST_CASE("an effect with strong evidence that does not predict left-out operating points is named, and the verdict says why it is not added",
          "[pmsm][diagnosis][findings]") {
    // The device servo's saturating iron on nine operating points (seed 1 of the study's clear case):
    // the search's evidence -69.9 and 62 % of the excess, but fitted without one operating point the
    // law predicts it better than base in 2 of 9.
    Diagnosis d = diagnosis_of_base();
    d.unpredictive.push_back({"saturation", -69.9, 0.62, 6, 2, 9});
    const auto f = findings_of(d, LackOfFit{}, 0.25);
    CHECK(says(f, "saturation would explain 62 % of what base leaves (dBIC -69.9 in the search over sets), but fitted without one operating "
                  "point it predicts that point better than base in only 2 of 9: the 9 operating points do not pin its 6 parameters, so it is "
                  "not added. More operating points (other currents and speeds) would decide."));
    CHECK_FALSE(says(f, "No missing effect: the residual is at the noise floor and no library effect earns its parameters."));
    CHECK(says(f, "No missing effect is recommended: the residual is at the noise floor, and the library effects with strong evidence do not "
                  "carry over to operating points they were not fitted to (below)."));
}

TEST_CASE("a set found step by step, with an effect pruned on the way", "[pmsm][diagnosis][findings]") {
    Diagnosis d = diagnosis_of_base();
    d.path.push_back(step(fit_of("base+deadtime", 0.1), StepKind::Added, "deadtime"));
    d.path.back().delta_bic = -50.0;
    d.path.push_back(step(fit_of("base+deadtime+encoder_offset", 0.02), StepKind::Added, "encoder_offset"));
    d.path.back().delta_bic = -20.0;
    d.path.back().signature = "harmonic 6 of the electrical angle";
    d.path.back().structure = 0.1;
    d.pruned = {"delay"};
    d.missing_effect_found = true;
    d.recommended_step = d.path.size() - 1;
    const auto f = findings_of(d, LackOfFit{}, 0.25);
    const auto missing = std::find_if(f.begin(), f.end(), [](const auto& s) { return s.rfind("Missing effects: deadtime and encoder_offset together", 0) == 0; });
    REQUIRE(missing != f.end());
    CHECK_THAT(*missing, Catch::Contains("step by step: +deadtime 0.1 V (dBIC -50.0), +encoder_offset 0.02 V (dBIC -20.0), to the noise floor of"));
    CHECK(says(f, "Some structure remains (harmonic 6 of the electrical angle), with 0.10 of the noise power: below the tolerance of 0.25. It is "
                  "the size of the steady-state model's own error on effects that make the currents ripple; a larger one would mean another "
                  "effect."));
    CHECK(says(f, "delay was added on the way and pruned again: the other effects of the set explain it."));
}

TEST_CASE("a tie, the missing effect outside the library, a hidden effect and a drift", "[pmsm][diagnosis][findings]") {
    Diagnosis tie = diagnosis_of_base();
    tie.tie = {"encoder_offset", "voltage_offset"};
    tie.tie_experiments = {{"the other direction", "omega_e = -100 rad/s", 0.5}};
    tie.missing_effect_found = true;
    auto f = findings_of(tie, tie.lack_of_fit, 0.25);
    CHECK(says(f, "Near tie: encoder_offset and voltage_offset explain the residual about equally well (dBIC within 6) or cannot be told "
                  "apart on this design; the data cannot say which is missing."));
    CHECK(says(f, "An experiment that would separate them: the other direction (omega_e = -100 rad/s)."));

    Diagnosis unknown = diagnosis_of_base();
    unknown.lack_of_fit.significant = true;
    unknown.lack_of_fit.signature_parts = {{0, "segment means of the u_q residual up to 30 mV"}};
    unknown.lack_of_fit.signature = unknown.lack_of_fit.signature_without({});
    unknown.not_in_library = true;
    Candidate hidden;
    hidden.effect = "delay";
    hidden.verdict = Verdict::NotIdentifiable;
    unknown.candidates = {hidden};
    unknown.drifts = {{"Rs", "temp_winding", 0.95, 0.18}, {"Ld", "", 0.0, 0.0}};
    f = findings_of(unknown, unknown.lack_of_fit, 0.25);
    CHECK(says(f, "No set of library effects reaches the noise floor with plausible values: the missing effect is not in the library. The "
                  "signature: segment means of the u_q residual up to 30 mV."));
    CHECK(says(f, "Not identifiable from this data (absorbed by the model's parameters without trace): delay."));
    CHECK(says(f, "delay: none of the extra operating points tried, alone or together, would make a tenth of its signature its own."));
    CHECK(f.back() == "The apparent Rs drifts with temp_winding across segments (r = 0.95, 0.18 Ohm per K).");
}

TEST_CASE("a harmonic outside the library that a model at the floor leaves is named once, and the rest of the signature after it",
          "[pmsm][diagnosis][findings]") {
    Diagnosis d = diagnosis_of_base();
    d.path.front().at_noise_floor = true;
    d.not_in_library = true;
    Harmonic second;
    second.order = 2;
    second.amplitude = {0.11, 0.422};
    second.standard_error = 0.031;
    second.significant = true;
    d.outside_harmonics = {second};
    d.lack_of_fit.significant = true;
    d.lack_of_fit.signature_parts = {{0, "segment means of the u_q residual up to 231 mV"},
                                     {2, "harmonic 2 of the electrical angle (110 mV on u_d, 422 mV on u_q, noise 31 mV)"},
                                     {5, "harmonic 5 of the electrical angle (1 mV on u_d, 90 mV on u_q, noise 31 mV)"}};
    CHECK(d.lack_of_fit.signature_without({2}) ==
          "segment means of the u_q residual up to 231 mV; harmonic 5 of the electrical angle (1 mV on u_d, 90 mV on u_q, noise 31 mV)");
    CHECK(d.lack_of_fit.signature_without({2, 5}) == "segment means of the u_q residual up to 231 mV");
    const auto f = findings_of(d, d.lack_of_fit, 0.25);
    CHECK(says(f, "What base leaves is within the noise floor's tolerance, but it holds harmonic 2 of the electrical angle (110 mV on u_d, 422 mV "
                  "on u_q, noise 31 mV; a negative-sequence fundamental: phase current sensors of unequal gain, or phases of unequal "
                  "impedance), an order that no library law makes at any size: the missing effect is not in the library. Besides it: segment "
                  "means of the u_q residual up to 231 mV; harmonic 5 of the electrical angle (1 mV on u_d, 90 mV on u_q, noise 31 mV)."));
    // Named alone, with nothing besides it: no empty list.
    d.lack_of_fit.signature_parts.erase(d.lack_of_fit.signature_parts.begin());
    d.lack_of_fit.signature_parts.pop_back();
    const auto alone = findings_of(d, d.lack_of_fit, 0.25);
    CHECK(std::none_of(alone.begin(), alone.end(), [](const std::string& s) { return s.find("Besides it") != std::string::npos; }));
    CHECK(std::any_of(alone.begin(), alone.end(), [](const std::string& s) { return s.ends_with("the missing effect is not in the library."); }));
}

TEST_CASE("a partial candidate's sentence agrees with the recommended path", "[pmsm][diagnosis][findings]") {
    Candidate partial;
    partial.effect = "psi_thermal";
    partial.verdict = Verdict::Partial;
    partial.explained = 0.83;
    partial.delta_bic = -400.0;
    partial.implausible = {"psi_thermal.alpha = -0.002 1/K sits at the lower end of its plausible range [-0.002, 0]"};
    const std::string alone = "Alone, psi_thermal explains 83 % of the excess residual (dBIC -400.0) but takes implausible values "
                              "(psi_thermal.alpha = -0.002 1/K sits at the lower end of its plausible range [-0.002, 0]): another effect is "
                              "still missing";

    // A near tie stops the search before it adds anything: the model diagnosed stays the recommendation.
    Diagnosis tie = diagnosis_of_base();
    tie.candidates = {partial};
    tie.tie = {"saturation", "deadtime"};
    tie.missing_effect_found = true;
    auto f = findings_of(tie, tie.lack_of_fit, 0.25);
    CHECK(says(f, alone + "; which one, the data cannot yet say (the near tie below)."));
    for (const auto& sentence : f) CHECK_THAT(sentence, !Catch::Contains("added it"));

    // The search added another effect beside the partial one: now it may say so.
    Diagnosis set = diagnosis_of_base();
    set.candidates = {partial};
    set.path.push_back(step(fit_of("base+rs_thermal", 0.1), StepKind::Added, "rs_thermal"));
    set.path.push_back(step(fit_of("base+rs_thermal+psi_thermal", 0.02), StepKind::Added, "psi_thermal"));
    set.path.back().at_noise_floor = true;
    set.recommended = set.path.back().fit.spec;
    set.missing_effect_found = true;
    set.recommended_step = set.path.size() - 1;
    f = findings_of(set, LackOfFit{}, 0.25);
    CHECK(says(f, alone + ", and the search over sets of effects added it."));

    // The recommended set holds only the partial effect itself: the other one was not added.
    Diagnosis alone_set = set;
    alone_set.path.erase(alone_set.path.begin() + 1);
    alone_set.recommended_step = alone_set.path.size() - 1;
    alone_set.recommended = parse_model_spec("base+psi_thermal");
    f = findings_of(alone_set, LackOfFit{}, 0.25);
    CHECK(says(f, alone + "."));

    // Nothing found and no tie: the sentence ends there.
    Diagnosis none = diagnosis_of_base();
    none.candidates = {partial};
    none.not_in_library = true;
    f = findings_of(none, none.lack_of_fit, 0.25);
    CHECK(says(f, alone + "."));
}

namespace {

// A harmonic at mechanical order 1 left by the model, against the logged angle or the integrated one.
MechanicalHarmonic once_per_turn(bool logged) {
    MechanicalHarmonic h;
    h.order = 1;
    h.pole_pairs = 16;
    h.amplitude = {0.004, 0.066};
    h.amplitude_standard_error = {0.001, 0.002};
    if (logged) h.phase = Eigen::Vector2d(-1.0, 0.6);
    h.phase_standard_error = {0.25, 0.03};
    h.significant = true;
    h.segments = 6;
    return h;
}

const std::string* finding_with(const std::vector<std::string>& findings, const std::string& text) {
    const auto it = std::find_if(findings.begin(), findings.end(), [&](const std::string& f) { return f.find(text) != std::string::npos; });
    return it == findings.end() ? nullptr : &*it;
}

}  // namespace

TEST_CASE("a harmonic at a mechanical order is named with its order, amplitude, phase and causes", "[pmsm][diagnosis][findings]") {
    Diagnosis d = diagnosis_of_base();
    d.lack_of_fit.significant = true;
    d.not_in_library = true;
    d.path.back().at_noise_floor = false;
    d.mechanical_left = {once_per_turn(true)};
    const auto f = findings_of(d, d.lack_of_fit, 0.25);
    const std::string* named = finding_with(f, "harmonic at mechanical order 1");
    REQUIRE(named);
    CHECK_THAT(*named, Catch::StartsWith("A harmonic at mechanical order 1 (once per turn, 1/16 of the electrical frequency) is left in the residual: "
                                         "amplitude 0.066 V on u_q and 0.004 V on u_d (± 0.002 V)"));
    CHECK_THAT(*named, Catch::Contains("phase 0.60 ± 0.03 rad against the logged mechanical angle"));
    CHECK_THAT(*named, Catch::Contains("rotor eccentricity, a bent shaft or a load with a once-per-turn torque"));

    d.mechanical_left = {once_per_turn(false)};
    const auto without_angle = findings_of(d, d.lack_of_fit, 0.25);  // kept: the finding points into it
    const std::string* integrated = finding_with(without_angle, "harmonic at mechanical order 1");
    REQUIRE(integrated);
    CHECK_THAT(*integrated, Catch::Contains("its phase is per segment"));
    CHECK_THAT(*integrated, !Catch::Contains("rad against"));
}

TEST_CASE("a mechanical-order harmonic under the noise floor's tolerance is called small, not a missing effect", "[pmsm][diagnosis][findings]") {
    Diagnosis d = diagnosis_of_base();
    d.path.back().at_noise_floor = true;
    d.mechanical_left = {once_per_turn(true)};
    const auto f = findings_of(d, d.lack_of_fit, 0.25);
    const std::string* named = finding_with(f, "harmonic at mechanical order 1");
    REQUIRE(named);
    CHECK_THAT(*named, Catch::StartsWith("A small harmonic at mechanical order 1"));
    CHECK_THAT(*named, Catch::Contains("so the verdict stands"));
    CHECK_THAT(*named, !Catch::Contains("No library effect has this signature"));
    CHECK_FALSE(finding_with(f, "missing effect is not in the library"));
}

TEST_CASE("an implausible addition after a complete plausible set is told apart from the recommendation", "[pmsm][diagnosis][findings]") {
    // The search reached the noise floor with base+deadtime, then added winding heating with values no
    // winding has; the recommendation is step 1 (diagnosis_stages.hpp, recommend), and the findings
    // say what was added after it and why it is left out, never that another effect is missing.
    Diagnosis d = diagnosis_of_base();
    d.path.push_back(step(fit_of("base+deadtime", 0.05, {{"deadtime.voltage", 0.28}}), StepKind::Added, "deadtime"));
    d.path.back().delta_bic = -500.0;
    d.path.back().at_noise_floor = true;
    d.path.push_back(step(fit_of("base+deadtime+rs_thermal", 0.0499, {{"deadtime.voltage", 0.28}, {"rs_thermal.alpha", 0.0035}}),
                          StepKind::Added, "rs_thermal"));
    d.path.back().delta_bic = -12.34;
    d.path.back().at_noise_floor = true;
    d.path.back().plausible = false;
    d.path.back().implausible = {"rs_thermal.alpha = 0.0035 at the lower end of its plausible range"};
    d.missing_effect_found = true;
    d.recommended_step = 1;
    d.recommended = d.path[1].fit.spec;
    d.winner = "deadtime";
    const auto f = findings_of(d, LackOfFit{}, 0.25);
    CHECK(says(f, "The search then added rs_thermal (0.0499 V rms, dBIC -12.3), but it takes implausible values (rs_thermal.alpha = 0.0035 at "
                  "the lower end of its plausible range): it is not recommended, and base+deadtime reaches the noise floor without it."));
    CHECK(std::none_of(f.begin(), f.end(), [](const std::string& s) { return s.rfind("Something else is missing", 0) == 0; }));
    const auto missing = std::find_if(f.begin(), f.end(), [](const auto& s) { return s.rfind("Missing effect: deadtime", 0) == 0; });
    CHECK(missing != f.end());
}

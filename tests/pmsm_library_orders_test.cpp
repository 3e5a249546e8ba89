// Which harmonics of the electrical angle the library's laws make (Effect::angle_orders), and a
// harmonic no law makes named as physics outside the library
// (problems/pmsm/diagnosis/library_orders.hpp).
#include <catch2/catch.hpp>

#include <filesystem>

#include "problems/pmsm/diagnosis/library_orders.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"

using namespace mhb::pmsm;

TEST_CASE("the library's laws make the rotor-frame harmonics their physics gives, and a set the sums and differences of two laws' orders",
          "[pmsm][diagnosis]") {
    // A stator-frame offset turns once per period in the rotor frame; the six-step dead-time loss and
    // the 5th and 7th flux harmonics turn at multiples of 6; the slot harmonics of the plugin example
    // (docs/examples/slot_harmonic.cpp, linked into the tests) at 12. Nothing at 2, 3, 4, ...
    const HarmonicOrders alone = orders_laws_make(parse_model_spec("base"));
    for (int k = 1; k <= harmonic_orders; ++k) {
        INFO("order " << k);
        CHECK(alone[static_cast<std::size_t>(k)] == (k == 1 || k == 6 || k == 12));
    }
    // Dead time's error on the current an offset makes ripple lies at 6 -+ 1.
    const HarmonicOrders set = orders_laws_make(parse_model_spec("base+deadtime+current_offset"));
    for (int k : {1, 5, 6, 7, 11, 12}) CHECK(set[static_cast<std::size_t>(k)]);
    for (int k : {2, 3, 4, 8, 9, 10}) CHECK_FALSE(set[static_cast<std::size_t>(k)]);
    // An effect that does not say which orders it makes claims every one.
    CHECK(Effect::every_angle_order().size() >= static_cast<std::size_t>(harmonic_orders));
}

TEST_CASE("a harmonic is outside the library when it is significant, relevant and at an order no law makes", "[pmsm][diagnosis]") {
    NoiseEstimate noise;
    noise.sigma = Eigen::Vector2d(0.5, 0.5);  // a relevant harmonic: rms over the axes >= 0.05 V
    LackOfFit left;
    const auto harmonic = [](int order, double amplitude, bool significant) {
        Harmonic h;
        h.order = order;
        h.amplitude = Eigen::Vector2d(0.0, amplitude);
        h.significant = significant;
        return h;
    };
    left.harmonics = {harmonic(1, 0.4, true), harmonic(2, 0.4, true), harmonic(3, 0.4, false), harmonic(4, 0.05, true), harmonic(6, 0.4, true)};
    const auto outside = harmonics_outside_library(left, parse_model_spec("base"), noise);
    REQUIRE(outside.size() == 1);
    CHECK(outside.front().order == 2);
}

TEST_CASE("a phase current sensor's gain error on the 5 kW machine is named not in the library by its second harmonic, and its clean drives "
          "are not",
          "[pmsm][diagnosis][hidden]") {
    // The device plant measures phase a 2 % high (detection_study_5kw.toml's case outside the
    // library): the controller then drives a current whose rotor-frame image turns at 2 theta, and
    // the voltage carries it. Below the floor's tolerance (0.11 of the noise power on seed 1) it was
    // called "at the noise floor" in 20 of 20 drives of the study. Seeds the study does not use.
    const auto profile = std::filesystem::path(MHBENCH_SOURCE_DIR) / "experiments" / "pmsm" / "device_5kw_profile.toml";
    int named = 0, clean_quiet = 0;
    constexpr int seeds = 3;
    for (int seed = 101; seed < 101 + seeds; ++seed)
        for (const double gain : {1.0, 1.02}) {
            auto drive = read_simulation_profile(profile);
            drive.seed = static_cast<std::uint64_t>(seed);
            drive.device->current_sensors.gain_a = gain;
            DiagnosisOptions options;
            options.pole_pairs = drive.motor.pole_pairs;
            const Diagnosis d = diagnose(simulate(drive).data, parse_model_spec("base"), options);
            INFO("seed " << seed << ", gain " << gain << ": recommended " << d.recommended.text() << (d.not_in_library ? ", not in the library" : ""));
            if (gain == 1.0) {
                CHECK(d.outside_harmonics.empty());
                clean_quiet += d.recommended.effects.empty() && !d.not_in_library ? 1 : 0;
                continue;
            }
            const bool second = d.outside_harmonics.size() == 1 && d.outside_harmonics.front().order == 2;
            named += d.not_in_library && second && d.recommended.effects.empty() ? 1 : 0;
            CHECK(std::any_of(d.findings.begin(), d.findings.end(), [](const std::string& f) {
                return f.find("harmonic 2 of the electrical angle") != std::string::npos && f.find("not in the library") != std::string::npos;
            }));
        }
    CHECK(named == seeds);
    CHECK(clean_quiet == seeds);
}

// Raw simulated logs, without a segment column (the simulator's logging.transients and
// logging.segment = false): the operating points found in them against the profile's segments, the
// diagnosis of the raw log against that of the same drive's steady log with its segments, and the
// noise measured from the data against the simulated sensors' noise. Over several seeds and noise
// levels, on the servo of the seed paper (averaged and device plant) and the Baldor flux map.
#include <cmath>
#include <cstdio>
#include <string>

#include <catch2/catch.hpp>

#include "problems/pmsm/data/operating_points.hpp"
#include "problems/pmsm/diagnosis/diagnosis.hpp"
#include "problems/pmsm/diagnosis/noise.hpp"
#include "problems/pmsm/model/model_spec.hpp"
#include "problems/pmsm/simulation/drive_simulator.hpp"
#include "problems/pmsm/simulation/simulation_profile.hpp"

using namespace mhb::pmsm;

namespace {

struct Rates {
    int drives = 0, windows_match = 0, verdict_match = 0, noise_within = 0;
};

std::string verdict(const Diagnosis& d) {
    return d.recommended.text() + (d.not_in_library ? " / not in the library" : "") + (d.incomplete ? " / incomplete" : "");
}

Rates raw_log_rates(const std::string& profile, int first_seed, int seeds, bool print) {
    Rates rates;
    for (int seed = first_seed; seed < first_seed + seeds; ++seed) {
        // Noise levels from half to twice the profile's, so that nothing is judged at one level.
        const double level = std::array{1.0, 0.5, 2.0}[static_cast<std::size_t>(seed % 3)];
        auto make = [&](bool raw, bool noisy) {
            auto spec = read_simulation_profile(std::string(MHBENCH_SOURCE_DIR) + "/experiments/pmsm/" + profile);
            spec.seed = static_cast<std::uint64_t>(seed);
            spec.noise.current *= noisy ? level : 0.0;
            spec.noise.speed *= noisy ? level : 0.0;
            spec.noise.voltage *= noisy ? level : 0.0;
            spec.logging.transients = raw;
            spec.logging.segment = !raw;
            return spec;
        };
        const auto steady_spec = make(false, true);
        const auto steady = simulate(steady_spec);
        const auto clean = simulate(make(false, false));
        auto raw = simulate(make(true, true));
        ++rates.drives;

        const auto points = find_operating_points(raw.data);
        // A found window matches its segment when it ends within 2 rows of the segment's last
        // steady row (a drive logs its new voltage reference in the sample its reference changes,
        // and the logging filter spreads a step over a row or two), covers the steady window from
        // within 2 rows of its start, and starts no earlier than the segment's own settling.
        bool match = points.windows.size() == raw.segments.size();
        for (std::size_t s = 0; match && s < raw.segments.size(); ++s) {
            const auto& w = points.windows[s];
            const auto& t = raw.segments[s];
            match = std::abs(w.first + w.rows - (t.first_row + t.rows)) <= 2 && w.first <= t.first_row + 2 &&
                    w.first >= t.settle_first_row;
            if (!match && print)
                std::printf("  window %zu: rows [%ld, %ld), segment settles from %ld, steady [%ld, %ld)\n", s, static_cast<long>(w.first),
                            static_cast<long>(w.first + w.rows), static_cast<long>(t.settle_first_row), static_cast<long>(t.first_row),
                            static_cast<long>(t.first_row + t.rows));
        }
        rates.windows_match += match ? 1 : 0;

        DiagnosisOptions options;
        options.pole_pairs = steady_spec.motor.pole_pairs;
        const auto spec = parse_model_spec("base");
        const auto on_steady = diagnose(steady.data, spec, options);
        const auto found = select_operating_points(std::move(raw.data), points);
        const auto on_raw = diagnose(found, spec, options);
        const bool same = verdict(on_steady) == verdict(on_raw);
        rates.verdict_match += same ? 1 : 0;

        const Eigen::Vector2d truth = sensor_noise_in_residual(steady_spec.motor, steady.data, clean.data);
        const Eigen::Vector2d measured = on_raw.noise.window.sigma;
        const bool within = (measured.array() / truth.array() - 1.0).abs().maxCoeff() <= 0.2;
        rates.noise_within += within ? 1 : 0;
        if (print)
            std::printf("%s seed %d noise x%.1f: %zu windows (%zu segments)%s, %ld transient rows; verdict steady '%s' raw '%s'; "
                        "noise u_d %.4g V (simulated %.4g), u_q %.4g V (simulated %.4g)%s; residual's u_d %.4g u_q %.4g\n",
                        profile.c_str(), seed, level, points.windows.size(), raw.segments.size(), match ? "" : " MISMATCH",
                        static_cast<long>(points.transient_rows), verdict(on_steady).c_str(), verdict(on_raw).c_str(), measured[0],
                        truth[0], measured[1], truth[1], within ? "" : " OUTSIDE 20 %", on_raw.noise.sigma[0], on_raw.noise.sigma[1]);
    }
    return rates;
}

// Windows: a false change splits a window now and then (the false-alarm probability is 1 % per log
// and scale, and each window's head is tested again at four times the bandwidth), so one drive in
// six may miss. The noise estimate must hold in every drive. The verdict is checked where the raw
// log holds no more steady rows than the diagnosis needs to agree: on the averaged servo. On the
// device servo and the Baldor map the found windows are two to four times the profile's steady
// windows (the settling the profile waits out is mostly steady), and the diagnosis of the longer
// log differs at the margin (docs/diagnosis.md, "Operating points found in a raw log").
void check_rates(const std::string& profile, int seeds, bool verdict_must_agree) {
    const auto r = raw_log_rates(profile, 101, seeds, false);
    INFO(profile << ": windows match in " << r.windows_match << ", verdict as on the steady log in " << r.verdict_match
                 << ", noise within 20 % in " << r.noise_within << " of " << r.drives << " drives");
    CHECK(r.windows_match >= r.drives - 1);
    CHECK(r.noise_within == r.drives);
    if (verdict_must_agree) CHECK(r.verdict_match == r.drives);
}

}  // namespace

TEST_CASE("raw logs of the servo on the averaged plant: operating points, verdict and noise", "[pmsm][raw_log]") {
    check_rates("diagnosis_profile.toml", 6, true);
}

TEST_CASE("raw logs of the servo on the device plant: operating points, verdict and noise", "[pmsm][raw_log]") {
    check_rates("device_diagnosis_profile.toml", 6, false);
}

TEST_CASE("raw logs of the Baldor flux map: operating points, verdict and noise", "[pmsm][raw_log]") {
    check_rates("flux_map_diagnosis_profile.toml", 6, false);
}

// The acceptance measurement, 20 seeds each, printed drive by drive (docs/diagnosis.md):
//   build/mhbench_tests "[raw_log_rates]" -s
TEST_CASE("raw-log rates over 20 seeds", "[.][raw_log_rates]") {
    for (const char* profile : {"diagnosis_profile.toml", "device_diagnosis_profile.toml", "flux_map_diagnosis_profile.toml"}) {
        const auto r = raw_log_rates(profile, 1, 20, true);
        std::printf("%s: windows match %d, verdict as steady %d, noise within 20 %% %d, of %d drives\n", profile, r.windows_match,
                    r.verdict_match, r.noise_within, r.drives);
    }
}

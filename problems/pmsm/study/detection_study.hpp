#pragma once
// The hidden-effect study (docs/effects.md, "Detection rates, measured"): drives simulated with
// known imperfections, over many noise seeds, diagnosed blind; how often the recommended model is
// the truth, how often clean data raise a false alarm, how well the base parameters come back.
//
// A study file (TOML, experiments/pmsm/detection_study.toml) names a simulation profile and, for each
// library effect, the profile settings that make it appear at two magnitudes (one clear, one near
// the detection limit). Settings are nested TOML tables merged into the profile, so a study works
// on the averaged plant (`effects.deadtime.voltage = 0.28`) and on the device plant
// (`plant.inverter.dead_time = 1e-6`) alike. Cases: clean data, each effect alone at both
// magnitudes, pairs and listed triples at the clear magnitude, and effects the library lacks.
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "problems/pmsm/diagnosis/diagnosis.hpp"

namespace mhb::pmsm {

struct StudyEffect {
    std::string name;            // the library effect the diagnosis should recommend
    // How the study's cases, pairs and triples name it: the effect's name unless the file gives a
    // `label`, which lets one effect appear at more sizes than clear and near the limit
    // (psi_thermal_10K, psi_thermal_60K).
    std::string label;
    std::string clear, weak;     // profile settings, TOML text of nested tables (weak empty: no near-limit case)
    std::string clear_as_written, weak_as_written;  // the same, as the study file writes them (for tables)
    bool in_combinations = true; // also in "all" pairs
    long line = 0;               // in the study file
    // The true size of the effect in the model's own parameters ("deadtime.voltage" = 0.28), as the
    // study's author knows it from the plant's settings; empty: not stated. A missed effect whose every
    // stated size lies below the detection limit the diagnosis printed for it was "below the limit".
    std::map<std::string, double> clear_size, weak_size;
    // For a plant whose law the library's only approximates (saturating iron, a measured flux map),
    // no setting states the size in the model's parameters: `pseudo_true_size = true` takes it from
    // the library law fitted to the same drive without sensor noise (its pseudo-true values), drive
    // by drive. Exclusive with clear_size and weak_size.
    bool pseudo_true_size = false;
};

struct StudyOutside {
    std::string name;            // an effect the library lacks
    std::string settings;        // profile settings, TOML text
    std::string settings_as_written;
    long line = 0;
    // A profile of its own (resolved; empty: the study's), for an effect whose signature needs another
    // design: a harmonic at a mechanical order shows only in segments that turn the shaft a whole turn.
    std::filesystem::path profile;
    std::string profile_text;
    // The mechanical order the diagnosis must name for the drive to count as correct (0: none).
    int mechanical_order = 0;
};

// Settings for a case that holds all of `effects` (two imperfections of one device, e.g. winding and
// magnet heating in one thermal network): merged last, they settle what the effects' own settings
// would set differently.
struct StudyTogether {
    std::vector<std::string> effects;  // sorted
    std::string settings;
    long line = 0;
};

// A variant of the profile every case runs on (other speeds, currents, noise, another machine):
// its settings are merged into the profile before the case's own, which win where both set a key.
struct StudyDesign {
    std::string name, description;
    std::string settings;        // TOML text of nested tables
    long line = 0;
};

struct StudySpec {
    std::filesystem::path file;        // the study file
    std::string name, description;
    std::filesystem::path profile;     // the simulation profile, resolved
    std::string profile_text;          // its text, read once (every drive merges its settings into it)
    std::string model = "base";        // the model diagnosed
    std::vector<std::uint64_t> seeds;  // noise seeds
    std::vector<StudyEffect> effects;
    bool all_pairs = true;             // every pair of effects
    std::vector<std::vector<std::string>> pairs;    // when not all
    std::vector<std::vector<std::string>> triples;
    std::vector<StudyOutside> outside;
    std::vector<StudyTogether> together;
    std::vector<StudyDesign> designs;  // none: every case runs on the profile as it is
    // Library effects the profile itself holds in every drive (a measured flux map is saturation):
    // part of every case's truth, so "clean" means "the profile's own effects alone".
    std::vector<std::string> profile_effects;  // sorted
    // Whether the diagnosis is told the device plant's current-loop bandwidth (`current_loop = true`;
    // diagnose --current-bandwidth): its models then pass dead time's and flux harmonics' voltages through the loop.
    bool current_loop = false;
    std::filesystem::path output;      // resolved against the study file's directory
    std::filesystem::path keep_data;   // when set, each drive's measurement is written here (CASE_seedN.csv and sidecar)
    std::string only;                  // when set, only cases whose label (design/label with designs) contains it
};

// Reads and checks a study file (InputError naming the file, line and field).
StudySpec read_study(const std::filesystem::path& path);

// One simulated drive of the study: which imperfections, at which magnitude.
struct StudyCase {
    std::string label;                  // "deadtime", "deadtime+rs_thermal", "clean", "outside:phase_gain"
    std::string kind;                   // clean, single, pair, triple, outside
    std::string magnitude;              // clear, weak (empty for clean)
    std::vector<std::string> truth;     // library effects present (sorted)
    bool outside = false;               // an effect the library lacks is present
    std::string settings;               // merged settings, TOML text
    std::map<std::string, std::map<std::string, double>> sizes;  // per effect present, its stated true sizes
    std::vector<std::string> pseudo_true_sized;  // effects present whose sizes each drive fits (StudyEffect::pseudo_true_size)
    std::string design;                 // the [[design]] it runs on (empty: the profile as it is)
    std::string design_settings;        // its settings, TOML text, merged into the profile before `settings`
    std::filesystem::path profile;      // the case's own profile (empty: the study's)
    std::string profile_text;
    int mechanical_order = 0;           // must be named for the drive to count as correct (0: none)
};

std::vector<StudyCase> study_cases(const StudySpec& spec);

// "deadtime", or "high_speed/deadtime" on a design: how messages, --only and file names call a case.
inline std::string case_name(const StudyCase& c) { return c.design.empty() ? c.label : c.design + "/" + c.label; }

struct StudyRecord {
    std::size_t case_index = 0;
    std::uint64_t seed = 0;
    std::string recommended;            // the recommended model
    std::vector<std::string> found;     // its effects beyond the model diagnosed (sorted)
    bool correct = false;               // found == truth (and, with an outside effect, "not in the library" said and its mechanical order named)
    bool not_in_library = false;
    bool tie = false;
    bool incomplete = false;            // recommended, and "something else is missing" said
    bool intervals_valid = true;        // the diagnosis did not mark the recommended model's intervals not valid
    // Per base parameter (Rs, Ld, Lq, psi_f): its interval came with a mark, not valid or a caveat
    // that concerns it (Diagnosis::recommended_interval_marked).
    std::array<bool, 4> interval_marked{};
    std::vector<int> mechanical_orders; // harmonics at mechanical orders the findings named (left beyond chance)
    std::vector<std::string> false_positives, missed;
    std::vector<DetectionLimit> missed_limits;  // the detection limits the diagnosis printed for the missed effects
    // Missed effects whose every stated size is below the limit printed for it: the log could not show them.
    std::vector<std::string> below_limit;
    // The case's pseudo-true-sized effects (StudyCase::pseudo_true_sized) on this drive without noise:
    // their size parameters fitted there (parameter -> value), and, since those trade against each
    // other, what the whole law shows on this log: the likelihood ratio it gains over the model
    // without it, in the noise the diagnosis measured, against what the search needs for that many
    // parameters, and the rms voltage it changes against the relevant voltage (detection_limits.hpp
    // states the same two thresholds per parameter). Below either, the effect is below this log's limit.
    std::map<std::string, double> pseudo_true_size;
    double pseudo_true_evidence = std::nan(""), pseudo_true_needed = std::nan("");
    double pseudo_true_voltage = std::nan(""), pseudo_true_relevant = std::nan("");  // V
    bool pseudo_true_below() const { return pseudo_true_evidence < pseudo_true_needed || pseudo_true_voltage < pseudo_true_relevant; }
    // Every effect missed is below its limit, nothing false was added and no "not in the library" was
    // said (structure left means something above the noise): the answer is right for this log.
    bool right_for_this_log() const {
        return correct || (false_positives.empty() && !not_in_library && !missed.empty() && below_limit.size() == missed.size());
    }
    Eigen::Vector4d base_error = Eigen::Vector4d::Zero();  // (fitted - true) / true of Rs, Ld, Lq, psi_f, recommended model
    // The control period's sample and hold on those (Diagnosis::sample_and_hold, relative to the true
    // values), when the diagnosis was told the period; base_error and covered are then of the corrected values.
    std::optional<Eigen::Vector4d> sample_and_hold_bias;
    // And the noise the logged current and voltage share (Diagnosis::shared_noise, relative to the
    // true values), when the diagnosis could measure it; base_error and covered are of the values
    // corrected for it, the intervals widened by its standard error.
    std::optional<Eigen::Vector4d> shared_noise_bias;
    // Whether the recommended model's 95 % interval of Rs, Ld, Lq, psi_f holds the true value: 1 yes,
    // 0 no, -1 no interval (the data do not determine it).
    std::array<int, 4> covered{-1, -1, -1, -1};
    // Power of the significant structure the recommended model leaves in the residual, relative to
    // the noise's (0: none significant): what a misspecification mark on the intervals would read.
    double structure_left = 0.0;
    // Where the plant's flux linkage is not linear (saturating iron, a measured map): the recommended
    // model's flux at the logged currents against the plant's, rms relative error (NaN otherwise).
    double flux_error = std::nan("");
    double rms = 0.0, rms_recommended = 0.0, noise = 0.0;  // V
    // A raw log (the profile logs transients without a segment column): the steady windows found in
    // it (0: the log had its segments), and per axis (u_d, u_q, V) the noise the diagnosis measured
    // from the data (window_noise) against the simulated sensors' noise as the true model's
    // residual sees it (the same drive simulated without noise, over the found windows).
    std::size_t windows = 0;
    Eigen::Vector2d noise_from_data = Eigen::Vector2d::Constant(std::nan(""));
    Eigen::Vector2d noise_simulated = Eigen::Vector2d::Constant(std::nan(""));
    bool raw() const { return windows > 0; }
    double seconds = 0.0;               // simulate + diagnose, wall
};

struct StudyRun {
    std::vector<StudyCase> cases;
    std::vector<StudyRecord> records;   // case-major, then seed order
};

// Runs every case (from study_cases, or some of them) at every seed in parallel (TBB); the records do not depend on the thread count.
// `progress` (optional) is called after each finished drive with the count done and the total.
StudyRun run_study(const StudySpec& spec, std::vector<StudyCase> cases, const DiagnosisOptions& options,
                   const std::function<void(std::size_t, std::size_t)>& progress = {});

// The simulation profile of one case at one seed, as TOML text (the profile with the case's settings
// and the seed merged in).
std::string case_profile(const StudySpec& spec, const StudyCase& c, std::uint64_t seed);

// table.md: rates per case with Wilson 95 % intervals, summaries per kind; table.csv: the same per case.
std::string study_markdown(const StudySpec& spec, const StudyRun& run);
std::string study_csv(const StudyRun& run);
nlohmann::ordered_json study_record_json(const StudyRun& run, const StudyRecord& r);

// Wilson score interval for k successes in n trials at 95 %.
std::pair<double, double> wilson_interval(std::size_t k, std::size_t n);

}  // namespace mhb::pmsm

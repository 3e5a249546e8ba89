#pragma once
// Two result sets of one experiment hold the same trials with the same outcomes, bit for bit: what a
// run must give whatever its thread count, interruptions or division into shards (time aside).
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "framework/trial.hpp"

namespace mhb::testing {

inline std::map<std::tuple<std::string, std::string, std::int64_t>, TrialRecord> by_key(const std::vector<TrialRecord>& records) {
    std::map<std::tuple<std::string, std::string, std::int64_t>, TrialRecord> out;
    for (const auto& r : records) out[{r.optimizer, r.problem, r.trial}] = r;
    return out;
}

inline void require_same_results(const std::vector<TrialRecord>& a, const std::vector<TrialRecord>& b) {
    const auto ka = by_key(a), kb = by_key(b);
    REQUIRE(ka.size() == a.size());
    REQUIRE(ka.size() == kb.size());
    for (const auto& [key, ra] : ka) {
        REQUIRE(kb.count(key) == 1);
        const auto& rb = kb.at(key);
        REQUIRE(ra.seed == rb.seed);
        REQUIRE(ra.ok == rb.ok);
        REQUIRE(ra.best_fitness == rb.best_fitness);  // bitwise
        REQUIRE(ra.best_position == rb.best_position);
        REQUIRE(ra.trace_best == rb.trace_best);
        REQUIRE(ra.trace_evaluations == rb.trace_evaluations);
        REQUIRE(ra.evaluations == rb.evaluations);
        REQUIRE(ra.iterations == rb.iterations);
    }
}

// table.csv of a results directory without its two run-time columns, the only fields a run's
// timing changes.
inline std::string table_csv_without_time(const std::filesystem::path& directory) {
    std::ifstream in(directory / "table.csv");
    std::string line, out;
    while (std::getline(in, line)) {
        for (int drop = 0; drop < 2; ++drop) line.erase(line.find_last_of(','));
        out += line + "\n";
    }
    return out;
}

}  // namespace mhb::testing

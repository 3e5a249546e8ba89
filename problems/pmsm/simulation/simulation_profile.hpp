#pragma once
// Simulation profiles (TOML) and the JSON sidecar written next to each simulated CSV. The profile
// schema is documented in docs/pmsm.md; every unknown key, wrong type or out-of-range value is an
// mhb::InputError naming the file, the line and the field.
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "problems/pmsm/simulation/drive_simulator.hpp"

namespace mhb::pmsm {

// Reads a profile; relative paths inside it resolve against the profile's directory.
DriveSimulation read_simulation_profile(const std::filesystem::path& path);
// Parses profile text; `source` names it in messages, `base_directory` resolves relative paths.
DriveSimulation parse_simulation_profile(const std::string& text, const std::string& source,
                                         const std::filesystem::path& base_directory);

// data.csv -> data.json
std::filesystem::path sidecar_path(const std::filesystem::path& csv);

// What a simulation was made with: true parameters, effects with their parameters, noise, seed,
// profile, and where each segment's rows are.
nlohmann::ordered_json simulation_sidecar(const DriveSimulation& spec, const SimulationResult& result,
                                          const std::string& profile);

// Writes data.csv and its sidecar data.json.
void write_simulation(const std::filesystem::path& csv, const DriveSimulation& spec, const SimulationResult& result,
                      const std::string& profile);

// The true base parameters (Rs, Ld, Lq, psi_f) recorded in the sidecar of `csv`, when there is one
// that has them. A sidecar that is not valid JSON is an InputError.
std::optional<Eigen::Vector4d> read_sidecar_truth(const std::filesystem::path& csv);

}  // namespace mhb::pmsm

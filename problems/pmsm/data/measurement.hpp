#pragma once
// A drive measurement: one row per logged sample, one column per signal, SI units, temperatures in °C.
// The same format holds simulated and real data (docs/data-format.md). Columns are stored as Eigen
// vectors so model evaluations run vectorised over samples.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "problems/pmsm/data/column_map.hpp"

namespace mhb::pmsm {

struct Measurement {
    std::string source;  // file the data came from (for messages), empty when built in memory

    // Required: controller-frame currents (A), reference voltages (V), electrical speed (rad/s).
    Eigen::VectorXd i_d, i_q, u_d, u_q, omega_e;
    // Optional: time (s), controller's electrical angle (rad), winding and magnet temperatures (°C),
    // the shaft's mechanical angle (rad; an absolute encoder or resolver: its zero is a fixed mark
    // on the shaft, so a harmonic's phase against it means the same in every segment).
    std::optional<Eigen::VectorXd> t, theta_e, temp_winding, temp_magnet, theta_m;
    // Optional operating-point label per row: segment[k] indexes segment_labels (labels in order of
    // first appearance). Both empty when the file has no segment column.
    std::vector<std::string> segment_labels;
    Eigen::VectorXi segment;

    // What the reader noticed but accepted (ignored columns, skipped blank lines).
    std::vector<std::string> warnings;

    // The drive's current loop, when its user states it (`--current-bandwidth`): its closed-loop
    // bandwidth (Hz, 0: not stated) and the delay from a sampled current to the voltage applied for
    // it (s; 1.5 control periods). The voltage of an effect with angle harmonics reaches the logged
    // reference through the loop (SteadyStateModel, docs/diagnosis.md, section 8).
    double current_loop_bandwidth = 0.0;
    double current_loop_delay = 0.0;

    Eigen::Index size() const { return i_d.size(); }
    bool has_segments() const { return !segment_labels.empty(); }
    // Resizes every present column (required ones always) to n rows.
    void resize(Eigen::Index n);
};

// The most rows a measurement may have (and a simulation profile may ask for): read, it takes 76
// bytes a row with every column, `mhbench fit` about 270 and `mhbench diagnose` about 800 bytes a row
// in all (measured at 10^6 rows, docs/performance.md), so a diagnosis stays near 4 GB.
inline constexpr std::int64_t max_measurement_rows = 5'000'000;

// The CSV reader reads a file in blocks of this size, twice (once to count the rows, once to parse
// them into columns allocated at their final size): large enough that a read is cheap next to
// parsing it, small next to the columns of a large file.
inline constexpr std::size_t csv_block_bytes = std::size_t{4} << 20;

// Names of the columns, in the order the writer emits them.
inline constexpr const char* required_columns[] = {"i_d", "i_q", "u_d", "u_q", "omega_e"};
inline constexpr const char* optional_columns[] = {"t", "segment", "theta_e", "temp_winding", "temp_magnet", "theta_m"};

enum class MeasurementFormat { Csv, Mat5, Mat73, Hdf5, OtherMat };

// The format of a file by its content, whatever its name: a "MATLAB 5.0 MAT-file" header (v5, v7),
// the HDF5 signature after a MATLAB header (v7.3), the HDF5 signature at 0, 512, 1024, ... (HDF5), a
// MATLAB header with neither (v4 or damaged), else CSV text. Csv also for what cannot be opened.
MeasurementFormat measurement_format(const std::filesystem::path& path);

// Reads a measurement from CSV, MAT (v5, v7, v7.3) or HDF5, as measurement_format decides, with the
// user's names and units mapped by `map` (docs/data-format.md). Throws mhb::InputError naming the
// file, the line or row, and the column or variable on a missing required column, a duplicate
// column, a non-numeric or non-finite value, a row with the wrong number of fields, columns of
// different lengths, an empty label, or a file without data rows. Unknown columns are ignored with a
// warning.
Measurement read_measurement(const std::filesystem::path& path, const ColumnMap& map = {});
// Parses CSV text; `source` names it in error messages.
Measurement parse_measurement(const std::string& text, const std::string& source, const ColumnMap& map = {});
// read_measurement for a file taken as CSV whatever its content, read `block_bytes` at a time (at
// least 3); a file that starts as some other binary format is refused as such. Tests choose small
// blocks to put block boundaries inside lines.
Measurement read_csv_measurement(const std::filesystem::path& path, const ColumnMap& map = {},
                                 std::size_t block_bytes = csv_block_bytes);

// Writes the present columns with a header; numbers in shortest round-trip form, so reading the file
// back gives the same doubles.
void write_measurement(const std::filesystem::path& path, const Measurement& m);
std::string format_measurement(const Measurement& m);

// The rows listed in `rows` (in that order), with segment labels renumbered. Given a measurement
// that is no longer needed, and rows that ascend strictly (as settled_rows lists them), the rows are
// selected in place, so that a large measurement is not held twice.
Measurement select_rows(const Measurement& m, const std::vector<Eigen::Index>& rows);
Measurement select_rows(Measurement&& m, const std::vector<Eigen::Index>& rows);

// Rows to keep when dropping the first `settle` seconds after every segment start (the first row and
// each row whose segment differs from the previous row's). Needs the t and segment columns.
std::vector<Eigen::Index> settled_rows(const Measurement& m, double settle);

}  // namespace mhb::pmsm

#include "problems/pmsm/data/measurement.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "framework/optional_library.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"
#include "problems/pmsm/data/text_file.hpp"

namespace mhb::pmsm {

void Measurement::resize(Eigen::Index n) {
    for (auto* v : {&i_d, &i_q, &u_d, &u_q, &omega_e}) v->resize(n);
    for (auto* v : {&t, &theta_e, &temp_winding, &temp_magnet, &theta_m})
        if (*v) (*v)->resize(n);
    if (has_segments()) segment.resize(n);
}

std::string_view csv_field_text(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
    // Spreadsheet exports quote fields; a quoted field is taken as its content (no embedded commas).
    if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
    return s;
}

// The vector that holds mhbench's numeric column `name` in `m`, created for an optional column.
Eigen::VectorXd* numeric_column(Measurement& m, const std::string& name) {
    if (name == "i_d") return &m.i_d;
    if (name == "i_q") return &m.i_q;
    if (name == "u_d") return &m.u_d;
    if (name == "u_q") return &m.u_q;
    if (name == "omega_e") return &m.omega_e;
    auto& slot = name == "t"              ? m.t
                 : name == "theta_e"      ? m.theta_e
                 : name == "theta_m"      ? m.theta_m
                 : name == "temp_winding" ? m.temp_winding
                                          : m.temp_magnet;
    slot.emplace();
    return &*slot;
}

// A value converted to mhbench's unit, refused when the conversion leaves the range of a double.
double converted(const UnitConversion& conversion, double value, const std::string& source, long line,
                 const std::string& field, const std::string& row) {
    const double out = conversion(value);
    if (!std::isfinite(out))
        throw InputError(source, line, field,
                         fmt::format("{}{} {} is beyond the range of a double after conversion", row, value, conversion.unit()));
    return out;
}

namespace {

// The file's format by its first bytes. A MAT v7.3 file is HDF5 behind a 512-byte MATLAB header;
// HDF5 looks for its signature at 0, 512, 1024, 2048, ... (after a user block), and so does this. A
// file cut short inside a signature or a MATLAB header keeps the format it started as, so that it is
// refused as a damaged file of that format, not parsed as CSV.
MeasurementFormat format_of(std::ifstream& in, std::uintmax_t size) {
    char head[20] = {};
    in.read(head, sizeof head);
    const std::string_view start(head, static_cast<std::size_t>(in.gcount()));
    // A whole file shorter than the header's first words is taken as that header cut short.
    for (const std::string_view header : {"MATLAB 5.0 MAT-file", "MATLAB 7.3 MAT-file"})
        if (start.starts_with(header) || (start.size() >= 4 && start.size() < header.size() && header.starts_with(start)))
            return header[7] == '5' ? MeasurementFormat::Mat5 : MeasurementFormat::Mat73;
    constexpr std::string_view hdf5_signature("\x89HDF\r\n\x1a\n", 8);
    for (std::uintmax_t offset = 0; offset + hdf5_signature.size() <= size; offset = offset == 0 ? 512 : 2 * offset) {
        char signature[8] = {};
        in.clear();
        in.seekg(static_cast<std::streamoff>(offset));
        in.read(signature, sizeof signature);
        if (in.gcount() == sizeof signature && std::string_view(signature, sizeof signature) == hdf5_signature)
            return offset > 0 && start.starts_with("MATLAB") ? MeasurementFormat::Mat73 : MeasurementFormat::Hdf5;
    }
    if (start.starts_with(hdf5_signature.substr(0, 4))) return MeasurementFormat::Hdf5;
    return start.starts_with("MATLAB") ? MeasurementFormat::OtherMat : MeasurementFormat::Csv;
}

// A numeric segment label as text: an integer within int's range, as a logger writes an
// operating-point number. Anything else (a fraction, -5.5e303) is damage, not a label.
std::string segment_label(double value, const std::string& source, const std::string& field, std::size_t row) {
    constexpr double least = -2147483648.0, most = 2147483647.0;
    if (!std::isfinite(value))
        throw InputError(source, 0, field, fmt::format("row {}: not a finite number: {}", row + 1, value));
    if (value != std::trunc(value) || value < least || value > most)
        throw InputError(source, 0, field,
                         fmt::format("row {}: segment label {} is not a whole number in [{}, {}] (numeric labels number the "
                                     "operating points; a damaged file?)",
                                     row + 1, value, least, most));
    return fmt::format("{}", static_cast<std::int64_t>(value));
}

Measurement measurement_from_file_columns(FileColumns file, const ColumnMap& map, const std::string& source) {
    Measurement m;
    m.source = source;
    m.warnings = std::move(file.notes);
    for (const auto& name : file.unused)
        m.warnings.push_back(fmt::format("{}: variable '{}' is not used by mhbench and was ignored", source, printable_field(name)));
    std::size_t rows = 0;
    for (auto& column : file.columns) {
        const std::string field = variable_field(column.name, column.column);
        const std::size_t n = static_cast<std::size_t>(column.labels ? column.labels->rows.size() : column.numbers.size());
        // The readers checked what each variable declared; this checks what they read.
        if (rows == 0) rows = n;
        if (n == 0 || n != rows) throw InputError(source, 0, field, fmt::format("{} rows read where {} were declared", n, rows));
        auto row = [](std::size_t r) { return fmt::format("row {}: ", r + 1); };
        if (column.column == "segment") {
            if (!column.labels) {
                TextColumn& text = column.labels.emplace();
                text.rows.resize(column.numbers.size());
                for (Eigen::Index r = 0; r < column.numbers.size(); ++r)
                    text.rows[r] = text.index_of(segment_label(column.numbers[r], source, field, static_cast<std::size_t>(r)));
                column.numbers = Eigen::VectorXd();
            }
            TextColumn& text = *column.labels;
            if (const auto empty = std::find(text.texts.begin(), text.texts.end(), ""); empty != text.texts.end()) {
                const int index = static_cast<int>(empty - text.texts.begin());
                Eigen::Index r = 0;
                while (text.rows[r] != index) ++r;
                throw InputError(source, 0, field, row(static_cast<std::size_t>(r)) + "empty segment label");
            }
            m.segment = std::move(text.rows);
            m.segment_labels = std::move(text.texts);
            continue;
        }
        if (column.labels) throw InputError(source, 0, field, "holds text; mhbench reads numbers here (only segment may be text)");
        const auto conversion = unit_conversion(map, column.column);
        for (std::size_t r = 0; r < n; ++r) {
            double& value = column.numbers[static_cast<Eigen::Index>(r)];
            if (!std::isfinite(value)) throw InputError(source, 0, field, fmt::format("{}not a finite number: {}", row(r), value));
            value = converted(conversion, value, source, 0, field, row(r));
        }
        // Moved, not copied: the column's memory becomes the measurement's.
        *numeric_column(m, column.column) = std::move(column.numbers);
    }
    return m;
}

}  // namespace

MeasurementFormat measurement_format(const std::filesystem::path& path) {
    std::error_code ec;
    // Nothing but a regular file is opened: opening a FIFO would wait for a writer.
    if (!std::filesystem::is_regular_file(path, ec)) return MeasurementFormat::Csv;
    std::ifstream in(path, std::ios::binary);
    if (!in) return MeasurementFormat::Csv;
    const auto size = std::filesystem::file_size(path, ec);
    return format_of(in, ec ? 0 : size);
}

Hdf5Reader hdf5_reader() {
    static const Hdf5Reader reader = optional_library_entry<Hdf5Reader()>("hdf5", "mhbench_hdf5_reader")();
    return reader;
}

Measurement read_binary_measurement(const std::filesystem::path& path, MeasurementFormat format, const ColumnMap& map,
                                    Isolation isolation) {
    const std::string source = path.string();
    const ColumnChoice choose = [&](const std::vector<std::string>& names) { return bind_columns(names, map, source, 0, "variable"); };
    if (format != MeasurementFormat::Mat5 && format != MeasurementFormat::Mat73 && format != MeasurementFormat::Hdf5)
        throw std::invalid_argument("read_binary_measurement: not a binary format");
    const Hdf5Layout layout = format == MeasurementFormat::Mat73 ? Hdf5Layout::matlab : Hdf5Layout::plain;
    // Debian's HDF5 is built without thread safety; trials may read their data in parallel, so
    // binary files are read one at a time, which costs little next to a fit.
    static std::mutex binary_reader;
    std::unique_lock lock(binary_reader);
    const Hdf5Reader read_hdf5 = format == MeasurementFormat::Mat5 ? nullptr : hdf5_reader();
    auto columns = format == MeasurementFormat::Mat5 ? read_mat5_columns(path, choose)
                   : isolation == Isolation::in_process
                       ? read_hdf5(path, choose, layout)
                       : read_in_child_process(source, "the HDF5 library", [&] { return read_hdf5(path, choose, layout); });
    lock.unlock();
    return measurement_from_file_columns(std::move(columns), map, source);
}

namespace {

Measurement read_measurement_of_format(const std::filesystem::path& path, const ColumnMap& map) {
    const std::string source = path.string();
    const MeasurementFormat format = measurement_format(path);
    switch (format) {
        case MeasurementFormat::Mat5:
        case MeasurementFormat::Mat73:
        case MeasurementFormat::Hdf5: return read_binary_measurement(path, format, map);
        case MeasurementFormat::OtherMat:
            throw InputError(source, 0, "",
                             "a MATLAB file that is neither v5/v7 nor v7.3; save it with save(file, '-v7') or '-v7.3'");
        case MeasurementFormat::Csv: break;
    }
    return read_csv_measurement(path, map);
}

}  // namespace

Measurement read_measurement(const std::filesystem::path& path, const ColumnMap& map) {
    require_regular_file(path, "measurement file");
    try {
        return read_measurement_of_format(path, map);
    } catch (const std::bad_alloc&) {
        // Every size is checked against the limits before it is allocated; what still fails is a
        // machine with less memory than the limits allow, and the file is what to name.
        throw InputError(path.string(), 0, "",
                         "out of memory while reading it; a smaller file (fewer rows or variables) or a machine with more memory");
    }
}

}  // namespace mhb::pmsm

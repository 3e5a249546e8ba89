// The CSV side of read_measurement: tokenising, the header's column plan, the two passes over the
// file's blocks (count, then parse into columns of their final size).
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
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"
#include "problems/pmsm/data/text_file.hpp"

namespace mhb::pmsm {
namespace {


// The fields of `line` into `fields`, which is reused from row to row to spare an allocation a row.
void split_fields(std::string_view line, std::vector<std::string_view>& fields) {
    fields.clear();
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = line.find(',', start);
        fields.push_back(csv_field_text(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
}

// What a header without the required columns most likely means, when the file uses another separator.
std::string separator_hint(std::string_view header_line) {
    if (header_line.find(';') != std::string_view::npos)
        return "; the header is separated by ';': mhbench reads comma-separated values with '.' as the decimal mark "
               "(export the CSV with ',' as separator and '.' as decimal point)";
    if (header_line.find('\t') != std::string_view::npos)
        return "; the header is separated by tabs: mhbench reads comma-separated values";
    return "";
}

bool is_blank(std::string_view line) {
    for (char c : line)
        if (c != ' ' && c != '\t' && c != '\r') return false;
    return true;
}

enum class ColumnRole { Numeric, Segment, Ignored };

struct ColumnPlan {
    std::string name;  // as messages show it: the file's name, and mhbench's when they differ
    ColumnRole role = ColumnRole::Ignored;
    Eigen::VectorXd* target = nullptr;
    UnitConversion to_mhbench_unit;
};

// A CSV field as a finite double; a leading '+' is allowed, which from_chars alone refuses.
double parse_number(std::string_view f, const std::string& source, long line, const std::string& field) {
    if (f.empty()) throw InputError(source, line, field, "empty value");
    std::string_view digits = f;
    if (digits.front() == '+') digits.remove_prefix(1);
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (ec == std::errc::result_out_of_range)
        throw InputError(source, line, field, fmt::format("value out of range: '{}'", printable_field(f)));
    if (ec != std::errc() || ptr != digits.data() + digits.size())
        throw InputError(source, line, field, fmt::format("not a number: '{}'", printable_field(f)));
    if (!std::isfinite(value))
        throw InputError(source, line, field, fmt::format("not a finite number: '{}'", printable_field(f)));
    return value;
}

constexpr std::string_view utf8_byte_order_mark("\xEF\xBB\xBF", 3);

// A text already in memory as one block: nothing to join, nothing to copy.
class TextBlocks {
public:
    explicit TextBlocks(std::string_view text) : text_(text) {}
    std::string_view next() { return std::exchange(text_rest_, std::string_view()); }
    void rewind() { text_rest_ = text_; }

private:
    std::string_view text_;
    std::string_view text_rest_ = text_;
};

// The blocks of a CSV source (TextBlocks, FileBlocks) after its byte-order mark, and no more than
// `limit` bytes of them: the second reading stops where the first did, so that a file a logger is
// still appending to reads the same both times.
template <class Blocks>
class CsvText {
public:
    explicit CsvText(Blocks& blocks, std::uintmax_t limit = UINTMAX_MAX) : blocks_(blocks), left_(limit) {}

    std::string_view next() {
        std::string_view block = blocks_.next();
        if (first_) {
            first_ = false;
            if (block.starts_with(utf8_byte_order_mark)) {
                bom_ = true;
                block.remove_prefix(utf8_byte_order_mark.size());
                if (block.empty()) block = blocks_.next();
            }
        }
        block = block.substr(0, static_cast<std::size_t>(std::min<std::uintmax_t>(block.size(), left_)));
        left_ -= block.size();
        return block;
    }
    bool byte_order_mark() const { return bom_; }

private:
    Blocks& blocks_;
    std::uintmax_t left_;
    bool first_ = true;
    bool bom_ = false;
};

// The lines of a CSV text without their '\n', as views into the current block. A line that crosses
// a block boundary is joined in a buffer of its own, so the memory beyond a block is one line.
template <class Blocks>
class CsvLines {
public:
    explicit CsvLines(CsvText<Blocks>& text) : text_(text) {}

    // The next line, valid until the next call; false after the last.
    bool next(std::string_view& line) {
        if (joined_returned_) {
            joined_.clear();
            joined_returned_ = false;
        }
        while (true) {
            if (const std::size_t nl = rest_.find('\n'); nl != std::string_view::npos) {
                line = rest_.substr(0, nl);
                rest_.remove_prefix(nl + 1);
                if (!joined_.empty()) {
                    joined_.append(line);
                    line = joined_;
                    joined_returned_ = true;
                }
                return true;
            }
            joined_.append(rest_);
            rest_ = text_.next();
            if (rest_.empty()) {
                // The last line, when the text does not end in '\n'.
                line = joined_;
                joined_returned_ = true;
                return !joined_.empty();
            }
        }
    }

private:
    CsvText<Blocks>& text_;
    std::string_view rest_;
    std::string joined_;
    bool joined_returned_ = false;
};

// What a first reading learns of a CSV text: all that the checks made before any column is
// allocated need, and the exact number of rows to allocate.
struct CsvShape {
    bool byte_order_mark = false;
    std::uintmax_t bytes = 0;               // after the byte-order mark
    bool has_text = false;                  // a byte other than white space
    std::optional<std::uintmax_t> nul;      // offset of the first NUL byte, after the byte-order mark
    long nul_line = 0;
    std::int64_t lines = 0;                 // split at '\n'; a last line without one counts when not empty
    std::int64_t data_rows = 0;             // the lines after the header that are not blank
};

template <class Blocks>
CsvShape shape_of(CsvText<Blocks>& text) {
    CsvShape s;
    bool blank = true, started = false;  // of the line being read: white space only so far, a byte so far
    auto end_line = [&] {
        ++s.lines;
        if (s.lines > 1 && !blank) ++s.data_rows;
        blank = true;
        started = false;
    };
    for (std::string_view block = text.next(); !block.empty(); block = text.next()) {
        if (!s.has_text) s.has_text = block.find_first_not_of(" \t\r\n") != std::string_view::npos;
        if (!s.nul)
            if (const std::size_t z = block.find('\0'); z != std::string_view::npos) {
                s.nul = s.bytes + z;
                s.nul_line = static_cast<long>(1 + s.lines + std::count(block.begin(), block.begin() + static_cast<std::ptrdiff_t>(z), '\n'));
            }
        for (std::string_view rest = block;;) {
            const std::size_t nl = rest.find('\n');
            const std::string_view part = rest.substr(0, nl);
            blank = blank && is_blank(part);
            started = started || !part.empty();
            if (nl == std::string_view::npos) break;
            end_line();
            rest.remove_prefix(nl + 1);
        }
        s.bytes += block.size();
    }
    if (started) end_line();
    s.byte_order_mark = text.byte_order_mark();
    return s;
}

// Reads a CSV text twice: first to count its rows, then to parse them straight into columns
// allocated once at their final size. Growing the columns row by row, or holding the text to split
// it, would cost two to eight times the memory of the data; a second reading of a file costs the
// system's page cache, not ours. `refuse_binary_start` is for files, which may be some other binary
// format: a NUL byte near the start names it as such.
template <class Blocks>
Measurement parse_csv(Blocks& blocks, const std::string& source, const ColumnMap& map, bool refuse_binary_start) {
    CsvText counting(blocks);
    const CsvShape shape = shape_of(counting);
    if (refuse_binary_start && shape.nul && *shape.nul + (shape.byte_order_mark ? utf8_byte_order_mark.size() : 0) < 4096)
        throw InputError(source, 0, "", "binary data that is neither CSV text, a MAT file (v5, v7, v7.3) nor HDF5");
    if (!shape.has_text) throw InputError(source, 0, "", "empty file: expected a header row and data rows");
    if (shape.nul) throw InputError(source, shape.nul_line, "", "binary data (a NUL byte), not a CSV text file");
    // Checked before any column is allocated, so that an oversized file costs no more than a block.
    if (shape.lines - 1 > max_measurement_rows)
        throw InputError(source, 0, "", fmt::format("{} rows after the header; the limit is {} rows", shape.lines - 1,
                                                     max_measurement_rows));

    long line_no = 1;
    // Only a file that changes between the two readings has other rows the second time.
    auto changed = [&] {
        return InputError(source, line_no, "", "the file changed while it was read; read it again once it is complete");
    };
    blocks.rewind();
    CsvText text(blocks, shape.bytes);
    CsvLines lines(text);
    std::string_view line;
    if (!lines.next(line)) throw changed();

    Measurement m;
    m.source = source;
    std::vector<std::string_view> fields;
    split_fields(line, fields);
    const std::size_t columns = fields.size();
    std::vector<ColumnPlan> plan(columns);
    std::map<std::string, std::size_t, std::less<>> seen;
    std::vector<std::string> names;
    for (std::size_t c = 0; c < columns; ++c) {
        const std::string name(fields[c]);
        if (name.empty())
            throw InputError(source, 1, fmt::format("column {}", c + 1), "empty column name in the header");
        if (auto it = seen.find(name); it != seen.end())
            throw InputError(source, 1, printable_field(name), fmt::format("duplicate column (columns {} and {})", it->second + 1, c + 1));
        seen.emplace(name, c);
        names.push_back(name);
    }
    const auto bound = bind_columns(names, map, source, 1, "column", separator_hint(line));
    const auto rows = static_cast<Eigen::Index>(shape.data_rows);
    for (std::size_t c = 0; c < columns; ++c) {
        plan[c].name = printable_field(column_label(names[c], bound[c]));
        if (bound[c].empty()) {
            m.warnings.push_back(fmt::format("{}: column '{}' is not used by mhbench and was ignored", source, printable_field(names[c])));
        } else if (bound[c] == "segment") {
            plan[c].role = ColumnRole::Segment;
            m.segment.resize(rows);
        } else {
            plan[c].role = ColumnRole::Numeric;
            plan[c].target = numeric_column(m, bound[c]);
            plan[c].target->resize(rows);
            plan[c].to_mhbench_unit = unit_conversion(map, bound[c]);
        }
    }
    if (rows == 0) throw InputError(source, static_cast<long>(shape.lines), "", "no data rows after the header");

    TextColumn segments;
    long blank_lines = 0;
    Eigen::Index row = 0;
    while (lines.next(line)) {
        ++line_no;
        if (is_blank(line)) {
            ++blank_lines;
            continue;
        }
        if (row == rows) throw changed();
        split_fields(line, fields);
        if (fields.size() != columns)
            throw InputError(source, line_no, "",
                             fmt::format("row has {} fields but the header has {}{}", fields.size(), columns,
                                         fields.size() > columns ? " (a decimal comma? numbers must use '.' as the decimal mark)" : ""));
        for (std::size_t c = 0; c < columns; ++c) {
            const auto f = fields[c];
            switch (plan[c].role) {
                case ColumnRole::Ignored: break;
                case ColumnRole::Segment: {
                    if (f.empty()) throw InputError(source, line_no, plan[c].name, "empty segment label");
                    m.segment[row] = segments.index_of(f);
                    break;
                }
                case ColumnRole::Numeric: {
                    const double value = parse_number(f, source, line_no, plan[c].name);
                    (*plan[c].target)[row] = converted(plan[c].to_mhbench_unit, value, source, line_no, plan[c].name, "");
                    break;
                }
            }
        }
        ++row;
    }
    if (row != rows) throw changed();
    if (blank_lines > 0)
        m.warnings.push_back(fmt::format("{}: {} blank line(s) skipped", source, blank_lines));
    m.segment_labels = std::move(segments.texts);
    return m;
}

}  // namespace


Measurement parse_measurement(const std::string& text, const std::string& source, const ColumnMap& map) {
    TextBlocks blocks(text);
    return parse_csv(blocks, source, map, false);
}

Measurement read_csv_measurement(const std::filesystem::path& path, const ColumnMap& map, std::size_t block_bytes) {
    require_regular_file(path, "measurement file");
    // Unreadable files are refused here, with the system's reason. The byte-order
    // mark is recognised in the first block, so a block holds at least that.
    FileBlocks file(path, "measurement file", std::max(block_bytes, utf8_byte_order_mark.size()));
    return parse_csv(file, path.string(), map, true);
}

}  // namespace mhb::pmsm

// What the measurement file readers share: the fields their refusals name, the row count every
// variable must declare, a MATLAB char matrix's rows as labels. The HDF5 reader, a library of its own
// (framework/optional_library.hpp), compiles this file too, so that it needs nothing from the program
// that loads it (the Python module loads it with its symbols kept local).
#include <cstdint>
#include <string>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

namespace mhb::pmsm {

std::string printable_field(std::string_view field) {
    constexpr std::size_t longest = 40;
    std::string out;
    for (std::size_t k = 0; k < field.size() && k < longest; ++k) {
        const auto c = static_cast<unsigned char>(field[k]);
        if (c < 0x20 || c >= 0x7f) out += fmt::format("\\x{:02X}", c);
        else out += static_cast<char>(c);
    }
    if (field.size() > longest) out += "...";
    return out;
}

std::string column_label(const std::string& name_in_file, const std::string& column) {
    return name_in_file == column || column.empty() ? name_in_file : fmt::format("{} ({})", name_in_file, column);
}

std::string variable_field(const std::string& name, const std::string& column) {
    return printable_field(column_label(name, column));
}

void DeclaredRows::check(const std::string& field, std::uint64_t rows) {
    if (rows == 0) throw InputError(source_, 0, field, "empty: no rows");
    if (rows > static_cast<std::uint64_t>(max_measurement_rows))
        throw InputError(source_, 0, field, fmt::format("{} rows; the limit is {} rows", rows, max_measurement_rows));
    if (first_.empty()) {
        first_ = field;
        rows_ = rows;
    } else if (rows != rows_) {
        throw InputError(source_, 0, field,
                         fmt::format("{} rows, but {} has {}; every column must have one value per row", rows, first_, rows_));
    }
}

namespace {

void append_utf8(std::uint32_t code, std::string& out) {
    if (code < 0x80) {
        out += static_cast<char>(code);
    } else if (code < 0x800) {
        out += static_cast<char>(0xC0 | (code >> 6));
        out += static_cast<char>(0x80 | (code & 0x3F));
    } else if (code < 0x10000) {
        out += static_cast<char>(0xE0 | (code >> 12));
        out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (code & 0x3F));
    } else {
        out += static_cast<char>(0xF0 | (code >> 18));
        out += static_cast<char>(0x80 | ((code >> 12) & 0x3F));
        out += static_cast<char>(0x80 | ((code >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (code & 0x3F));
    }
}

// The labels of a char matrix's rows, `append_row(r, text)` appending row r's characters, without
// the blanks MATLAB pads the shorter rows with.
template <class AppendRow>
TextColumn labels_by_row(std::size_t rows, AppendRow append_row) {
    TextColumn out;
    out.rows.resize(static_cast<Eigen::Index>(rows));
    std::string text;
    for (std::size_t r = 0; r < rows; ++r) {
        text.clear();
        append_row(r, text);
        while (!text.empty() && text.back() == ' ') text.pop_back();
        out.rows[static_cast<Eigen::Index>(r)] = out.index_of(text);
    }
    return out;
}

}  // namespace

TextColumn char_matrix_labels(const std::uint16_t* units, std::size_t rows, std::size_t width) {
    return labels_by_row(rows, [&](std::size_t r, std::string& text) {
        for (std::size_t c = 0; c < width; ++c) {
            std::uint32_t code = units[r + rows * c];
            if (code >= 0xD800 && code < 0xDC00 && c + 1 < width) {
                const std::uint32_t low = units[r + rows * (c + 1)];
                if (low >= 0xDC00 && low < 0xE000) {
                    code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
                    ++c;
                }
            }
            append_utf8(code, text);
        }
    });
}

TextColumn char_matrix_labels(const std::uint8_t* bytes, std::size_t rows, std::size_t width) {
    return labels_by_row(rows, [&](std::size_t r, std::string& text) {
        for (std::size_t c = 0; c < width; ++c) text += static_cast<char>(bytes[r + rows * c]);
    });
}

}  // namespace mhb::pmsm

// MAT files through matio (v5, v7 and v7.3; matio reads v7.3 through HDF5).
#include <cstdint>
#include <memory>
#include <mutex>

#include <fmt/format.h>
#include <matio.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

namespace mhb::pmsm {
namespace {

// matio reports through a process-wide log function, which by default writes to stderr; its
// messages are kept for the refusal instead. Readers may run on several threads, hence thread_local.
thread_local std::string* matio_messages = nullptr;

void keep_matio_message(int, char* message) {
    if (matio_messages && message) *matio_messages += (matio_messages->empty() ? "" : "; ") + std::string(message);
}

class MatioMessages {
public:
    MatioMessages() {
        static std::once_flag installed;
        std::call_once(installed, [] { Mat_LogInitFunc("mhbench", keep_matio_message); });
        matio_messages = &text_;
    }
    ~MatioMessages() { matio_messages = nullptr; }
    MatioMessages(const MatioMessages&) = delete;
    MatioMessages& operator=(const MatioMessages&) = delete;
    std::string reason() const { return text_.empty() ? std::string() : ": " + text_; }

private:
    std::string text_;
};

struct MatFileCloser {
    void operator()(mat_t* mat) const { Mat_Close(mat); }
};
struct MatVariableFree {
    void operator()(matvar_t* var) const { Mat_VarFree(var); }
};
using MatVariable = std::unique_ptr<matvar_t, MatVariableFree>;

const char* class_name(matio_classes c) {
    switch (c) {
        case MAT_C_EMPTY: return "empty array";
        case MAT_C_CELL: return "cell array";
        case MAT_C_STRUCT: return "struct";
        case MAT_C_OBJECT: return "object";
        case MAT_C_CHAR: return "char array";
        case MAT_C_SPARSE: return "sparse matrix";
        case MAT_C_FUNCTION: return "function handle";
        case MAT_C_OPAQUE: return "opaque object (a MATLAB string array or table? save it as a cell array of char or numeric vectors)";
        default: return "numeric array";
    }
}

std::string shape(const matvar_t* v) {
    std::string out;
    for (int d = 0; d < v->rank; ++d) out += (d ? "x" : "") + std::to_string(v->dims[d]);
    return out;
}

std::size_t elements(const matvar_t* v) {
    std::size_t n = 1;
    for (int d = 0; d < v->rank; ++d) n *= v->dims[d];
    return n;
}

bool is_vector(const matvar_t* v) { return v->rank == 2 && (v->dims[0] == 1 || v->dims[1] == 1); }

bool is_numeric(matio_classes c) { return c >= MAT_C_DOUBLE && c <= MAT_C_UINT64; }

template <class T>
void copy_numbers(const matvar_t* v, std::size_t n, Eigen::VectorXd& out) {
    const auto* data = static_cast<const T*>(v->data);
    out.resize(static_cast<Eigen::Index>(n));
    for (std::size_t k = 0; k < n; ++k) out[static_cast<Eigen::Index>(k)] = static_cast<double>(data[k]);
}

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

// The rows of a char matrix as UTF-8 strings, without the blanks MATLAB pads short rows with. MATLAB
// stores characters as UTF-16 and column-major; matio hands over 8-bit text when the file has it.
std::vector<std::string> char_rows(const matvar_t* v) {
    const std::size_t rows = v->rank == 2 ? v->dims[0] : 0, width = v->rank == 2 ? v->dims[1] : 0;
    std::vector<std::string> out(rows);
    const bool wide = v->data_size == 2;
    for (std::size_t r = 0; r < rows; ++r) {
        std::string& text = out[r];
        for (std::size_t c = 0; c < width; ++c) {
            const std::size_t k = r + rows * c;
            if (!wide) {
                text += static_cast<const char*>(v->data)[k];
                continue;
            }
            std::uint32_t code = static_cast<const std::uint16_t*>(v->data)[k];
            if (code >= 0xD800 && code < 0xDC00 && c + 1 < width) {
                const std::uint32_t low = static_cast<const std::uint16_t*>(v->data)[k + rows];
                if (low >= 0xDC00 && low < 0xE000) {
                    code = 0x10000 + ((code - 0xD800) << 10) + (low - 0xDC00);
                    ++c;
                }
            }
            append_utf8(code, text);
        }
        while (!text.empty() && text.back() == ' ') text.pop_back();
    }
    return out;
}

TextColumn text_column(const std::vector<std::string>& rows) {
    TextColumn out;
    out.rows.resize(static_cast<Eigen::Index>(rows.size()));
    for (std::size_t r = 0; r < rows.size(); ++r) out.rows[static_cast<Eigen::Index>(r)] = out.index_of(rows[r]);
    return out;
}

FileColumn column_from_variable(const matvar_t* v, std::string name) {
    FileColumn column;
    column.name = std::move(name);
    const std::size_t n = elements(v);
    if (n > 0 && !v->data && v->class_type != MAT_C_CELL) {
        column.unusable = "matio read no data for it";
        return column;
    }
    if (is_numeric(v->class_type)) {
        if (v->isComplex) column.unusable = fmt::format("a complex {} array; mhbench reads real numbers", shape(v));
        else if (!is_vector(v)) column.unusable = fmt::format("a {} matrix, not a vector", shape(v));
        else if (n > static_cast<std::size_t>(max_measurement_rows))
            column.unusable = fmt::format("{} rows; the limit is {} rows", n, max_measurement_rows);
        if (!column.unusable.empty()) return column;
        switch (v->class_type) {
            case MAT_C_DOUBLE: copy_numbers<double>(v, n, column.numbers); break;
            case MAT_C_SINGLE: copy_numbers<float>(v, n, column.numbers); break;
            case MAT_C_INT8: copy_numbers<std::int8_t>(v, n, column.numbers); break;
            case MAT_C_UINT8: copy_numbers<std::uint8_t>(v, n, column.numbers); break;
            case MAT_C_INT16: copy_numbers<std::int16_t>(v, n, column.numbers); break;
            case MAT_C_UINT16: copy_numbers<std::uint16_t>(v, n, column.numbers); break;
            case MAT_C_INT32: copy_numbers<std::int32_t>(v, n, column.numbers); break;
            case MAT_C_UINT32: copy_numbers<std::uint32_t>(v, n, column.numbers); break;
            case MAT_C_INT64: copy_numbers<std::int64_t>(v, n, column.numbers); break;
            default: copy_numbers<std::uint64_t>(v, n, column.numbers); break;
        }
        return column;
    }
    if (v->class_type == MAT_C_CHAR) {
        if (v->rank != 2 || v->data_size > 2) column.unusable = fmt::format("a {} char array in an unsupported encoding or shape", shape(v));
        else column.labels = text_column(char_rows(v));
        return column;
    }
    if (v->class_type == MAT_C_CELL) {
        if (!is_vector(v)) {
            column.unusable = fmt::format("a {} cell array, not a vector", shape(v));
            return column;
        }
        TextColumn labels;
        labels.rows.resize(static_cast<Eigen::Index>(n));
        for (std::size_t k = 0; k < n; ++k) {
            const matvar_t* cell = Mat_VarGetCell(const_cast<matvar_t*>(v), static_cast<int>(k));
            if (!cell || (cell->class_type != MAT_C_CHAR && elements(cell) > 0)) {
                column.unusable = fmt::format("row {}: the cell holds a {}, not text", k + 1,
                                              cell ? class_name(cell->class_type) : "nothing matio could read");
                return column;
            }
            const auto rows = elements(cell) == 0 ? std::vector<std::string>{""} : char_rows(cell);
            if (rows.size() != 1) {
                column.unusable = fmt::format("row {}: the cell holds a {} char matrix, not one line of text", k + 1, shape(cell));
                return column;
            }
            labels.rows[static_cast<Eigen::Index>(k)] = labels.index_of(rows[0]);
        }
        column.labels = std::move(labels);
        return column;
    }
    if (v->class_type == MAT_C_EMPTY) return column;
    column.unusable = fmt::format("a {} {}, not a vector", shape(v), class_name(v->class_type));
    return column;
}

}  // namespace

FileColumns read_mat_columns(const std::filesystem::path& path) {
    const std::string file = path.string();
    MatioMessages messages;
    std::unique_ptr<mat_t, MatFileCloser> mat(Mat_Open(file.c_str(), MAT_ACC_RDONLY));
    if (!mat) throw InputError(file, 0, "", "cannot read the MAT file" + messages.reason());

    std::vector<std::string> names, structs;
    while (MatVariable info{Mat_VarReadNextInfo(mat.get())}) {
        if (!info->name) continue;
        (info->class_type == MAT_C_STRUCT ? structs : names).emplace_back(info->name);
    }
    if (names.empty() && structs.empty())
        throw InputError(file, 0, "", "the MAT file holds no variables" + messages.reason());

    FileColumns out;
    auto read = [&](const std::string& name) {
        MatVariable v{Mat_VarRead(mat.get(), name.c_str())};
        if (!v) throw InputError(file, 0, name, "matio cannot read the variable" + messages.reason());
        return v;
    };
    if (names.empty() && structs.size() == 1) {
        const auto s = read(structs[0]);
        if (elements(s.get()) != 1)
            throw InputError(file, 0, structs[0],
                             fmt::format("a {} struct array; mhbench reads the fields of a single (1x1) struct", shape(s.get())));
        const unsigned fields = Mat_VarGetNumberOfFields(s.get());
        char* const* field_names = Mat_VarGetStructFieldnames(s.get());
        for (unsigned f = 0; f < fields; ++f) {
            const matvar_t* field = Mat_VarGetStructFieldByName(s.get(), field_names[f], 0);
            if (field) out.columns.push_back(column_from_variable(field, field_names[f]));
            else out.columns.push_back({field_names[f], {}, {}, "matio cannot read the field" + messages.reason()});
        }
        return out;
    }
    for (const auto& name : names) out.columns.push_back(column_from_variable(read(name).get(), name));
    for (const auto& name : structs)
        out.notes.push_back(fmt::format("{}: struct '{}' was ignored: the columns are the top-level variables (a struct's "
                                        "fields are the columns only when the file holds that one struct and nothing else)",
                                        file, name));
    return out;
}

}  // namespace mhb::pmsm

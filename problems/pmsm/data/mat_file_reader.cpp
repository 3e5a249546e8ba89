// MAT v5 files, and v7 files (v5 with each variable compressed by zlib), through mhbench's own
// parser of the format (MathWorks, "MAT-File Format", version 5). Not matio: matio finds a variable
// by reading every variable before it (quadratic in their number), drops zlib's errors into a log
// and carries on with whatever the buffer held, and allocates what a header declares before it
// knows the file holds it. Here the file's variables are listed in one pass over their tags; each
// length a tag declares is checked against what is left of the file (or of the decompressed
// variable) before it is used; only the variables that feed a column are read; and a compressed
// variable is inflated to its end, so that zlib checks its Adler-32 sum over every byte.
#include <algorithm>
#include <cstring>
#include <fstream>
#include <span>
#include <stdexcept>

#include <fmt/format.h>
#include <zlib.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

namespace mhb::pmsm {
namespace {

// Data types of the format's elements, and MATLAB's array classes.
enum DataType : std::uint32_t {
    mi_int8 = 1, mi_uint8 = 2, mi_int16 = 3, mi_uint16 = 4, mi_int32 = 5, mi_uint32 = 6, mi_single = 7, mi_double = 9,
    mi_int64 = 12, mi_uint64 = 13, mi_matrix = 14, mi_compressed = 15, mi_utf8 = 16, mi_utf16 = 17, mi_utf32 = 18
};
enum ArrayClass : std::uint8_t {
    mx_cell = 1, mx_struct = 2, mx_object = 3, mx_char = 4, mx_sparse = 5, mx_double = 6, mx_single = 7, mx_int8 = 8,
    mx_uint8 = 9, mx_int16 = 10, mx_uint16 = 11, mx_int32 = 12, mx_uint32 = 13, mx_int64 = 14, mx_uint64 = 15,
    mx_function = 16, mx_opaque = 17
};

constexpr std::size_t header_bytes = 128;
// A variable's array header (flags, dimensions, name) is read from at most this many bytes of it.
constexpr std::size_t array_header_bytes = 4096;
// The most bytes a variable other than a numeric vector may take once decompressed: a cell array of
// 5 million short labels takes about 320 MB.
constexpr std::size_t max_variable_bytes = std::size_t{1} << 30;

// What is wrong inside a variable's bytes; the reader names the file and the variable.
class Damage : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

const char* class_name(std::uint8_t c) {
    switch (c) {
        case mx_cell: return "cell array";
        case mx_struct: return "struct";
        case mx_object: return "object";
        case mx_char: return "char array";
        case mx_sparse: return "sparse matrix";
        case mx_function: return "function handle";
        case mx_opaque: return "opaque object (a MATLAB string array or table? save it as a cell array of char or numeric vectors)";
        default: return c >= mx_double && c <= mx_uint64 ? "numeric array" : "array of unknown class";
    }
}

std::size_t type_size(std::uint32_t type) {
    switch (type) {
        case mi_int8: case mi_uint8: case mi_utf8: return 1;
        case mi_int16: case mi_uint16: case mi_utf16: return 2;
        case mi_int32: case mi_uint32: case mi_single: case mi_utf32: return 4;
        case mi_double: case mi_int64: case mi_uint64: return 8;
        default: return 0;
    }
}

// Bytes in the file's byte order, every read checked against what is left.
class Bytes {
public:
    Bytes(std::span<const std::uint8_t> data, bool big_endian) : data_(data), big_endian_(big_endian) {}

    std::size_t left() const { return data_.size() - at_; }
    bool big_endian() const { return big_endian_; }
    std::span<const std::uint8_t> take(std::size_t n) {
        if (n > left()) throw Damage(fmt::format("{} bytes declared where {} are left", n, left()));
        const auto out = data_.subspan(at_, n);
        at_ += n;
        return out;
    }
    std::uint32_t u32() { return static_cast<std::uint32_t>(unsigned_value(take(4))); }

    // One element: its type and data, after the tag; the data's padding to 8 bytes is skipped.
    struct Element {
        std::uint32_t type;
        std::span<const std::uint8_t> data;
    };
    Element element() {
        const std::uint32_t first = u32();
        if (first >> 16) {
            // The small element format: type and byte count share the tag, the data its next 4 bytes.
            const std::uint32_t n = first >> 16;
            if (n > 4) throw Damage(fmt::format("a small element of {} bytes (at most 4)", n));
            return {first & 0xFFFF, take(4).first(n)};
        }
        const std::uint32_t n = u32();
        const auto data = take(n);
        take(std::min<std::size_t>((8 - n % 8) % 8, left()));
        return {first, data};
    }

    // An unsigned integer of 1 to 8 bytes in the file's byte order.
    std::uint64_t unsigned_value(std::span<const std::uint8_t> b) const {
        std::uint64_t v = 0;
        for (std::size_t k = 0; k < b.size(); ++k) v |= std::uint64_t{b[big_endian_ ? b.size() - 1 - k : k]} << (8 * k);
        return v;
    }

private:
    std::span<const std::uint8_t> data_;
    std::size_t at_ = 0;
    bool big_endian_;
};

// Element `k` of numeric data of type `type`, as a double (exact for integers up to 2^53).
double number_at(const Bytes& b, std::span<const std::uint8_t> data, std::uint32_t type, std::size_t k) {
    const std::size_t size = type_size(type);
    const std::uint64_t raw = b.unsigned_value(data.subspan(k * size, size));
    switch (type) {
        case mi_int8: return static_cast<std::int8_t>(raw);
        case mi_uint8: return static_cast<double>(raw);
        case mi_int16: return static_cast<std::int16_t>(raw);
        case mi_uint16: return static_cast<double>(raw);
        case mi_int32: return static_cast<std::int32_t>(raw);
        case mi_uint32: return static_cast<double>(raw);
        case mi_int64: return static_cast<double>(static_cast<std::int64_t>(raw));
        case mi_uint64: return static_cast<double>(raw);
        case mi_single: {
            float f;
            const auto bits = static_cast<std::uint32_t>(raw);
            std::memcpy(&f, &bits, sizeof f);
            return f;
        }
        default: {
            double d;
            std::memcpy(&d, &raw, sizeof d);
            return d;
        }
    }
}

// A variable's array header: class, flags, dimensions and name.
struct ArrayHeader {
    std::uint8_t array_class = 0;
    bool complex = false;
    std::vector<std::uint64_t> dims;
    std::string name;

    std::uint64_t elements() const {
        std::uint64_t n = 1;
        for (const auto d : dims) n = d != 0 && n > UINT64_MAX / d ? UINT64_MAX : n * d;
        return n;
    }
    bool vector() const { return dims.size() == 2 && (dims[0] == 1 || dims[1] == 1); }
    std::string shape() const {
        std::string out;
        for (std::size_t d = 0; d < dims.size(); ++d) out += (d ? "x" : "") + std::to_string(dims[d]);
        return out;
    }
};

// The header at the start of a miMATRIX element's data; `b` is left at what follows the name.
ArrayHeader array_header(Bytes& b) {
    ArrayHeader h;
    const auto flags = b.element();
    if (flags.type != mi_uint32 || flags.data.size() != 8) throw Damage("no array flags where a variable starts");
    const auto word = static_cast<std::uint32_t>(b.unsigned_value(flags.data.first(4)));
    h.array_class = static_cast<std::uint8_t>(word & 0xFF);
    h.complex = (word & 0x0800) != 0;
    const auto dims = b.element();
    if (dims.type != mi_int32 || dims.data.size() % 4 != 0 || dims.data.size() < 8 || dims.data.size() > 4 * 32)
        throw Damage("no dimensions (2 to 32 of them) after the array flags");
    for (std::size_t d = 0; d < dims.data.size(); d += 4) {
        const auto v = static_cast<std::int32_t>(b.unsigned_value(dims.data.subspan(d, 4)));
        if (v < 0) throw Damage(fmt::format("a negative dimension ({})", v));
        h.dims.push_back(static_cast<std::uint64_t>(v));
    }
    const auto name = b.element();
    if (name.type != mi_int8 && name.type != mi_uint8) throw Damage("no name after the dimensions");
    h.name.assign(name.data.begin(), name.data.end());
    return h;
}

// A MATLAB char array's units: UTF-16 code units, or bytes, one per character.
struct CharUnits {
    std::vector<std::uint16_t> wide;
    std::span<const std::uint8_t> bytes;
    bool is_wide = false;
};

// Decodes UTF-8 into UTF-16 code units; matio writes multi-byte text as UTF-8 of `count` characters.
std::vector<std::uint16_t> utf16_of_utf8(std::span<const std::uint8_t> s) {
    std::vector<std::uint16_t> out;
    for (std::size_t k = 0; k < s.size();) {
        std::uint32_t c = s[k];
        std::size_t extra = c < 0x80 ? 0 : c >= 0xF0 ? 3 : c >= 0xE0 ? 2 : c >= 0xC0 ? 1 : 0;
        if (c >= 0x80 && extra == 0) throw Damage("text that is not UTF-8");
        c = extra == 0 ? c : c & (0x3F >> extra);
        for (std::size_t e = 1; e <= extra; ++e) {
            if (k + e >= s.size() || (s[k + e] & 0xC0) != 0x80) throw Damage("text that is not UTF-8");
            c = (c << 6) | (s[k + e] & 0x3F);
        }
        k += extra + 1;
        if (c >= 0x10000) {
            c -= 0x10000;
            out.push_back(static_cast<std::uint16_t>(0xD800 + (c >> 10)));
            out.push_back(static_cast<std::uint16_t>(0xDC00 + (c & 0x3FF)));
        } else {
            out.push_back(static_cast<std::uint16_t>(c));
        }
    }
    return out;
}

CharUnits char_units(const Bytes& b, const Bytes::Element& data, std::uint64_t count) {
    CharUnits out;
    const std::size_t size = type_size(data.type);
    if (data.type == mi_utf16 || data.type == mi_uint16 || data.type == mi_int16) {
        if (data.data.size() != count * 2) throw Damage(fmt::format("{} characters declared, {} bytes of UTF-16 held", count, data.data.size()));
        out.is_wide = true;
        out.wide.resize(count);
        for (std::size_t k = 0; k < count; ++k) out.wide[k] = static_cast<std::uint16_t>(b.unsigned_value(data.data.subspan(2 * k, 2)));
        return out;
    }
    if (size != 1) throw Damage("characters stored in an unsupported encoding");
    if (data.data.size() == count) {
        out.bytes = data.data;
        return out;
    }
    if (data.type != mi_utf8) throw Damage(fmt::format("{} characters declared, {} bytes held", count, data.data.size()));
    out.wide = utf16_of_utf8(data.data);
    if (out.wide.size() != count) throw Damage(fmt::format("{} characters declared, {} held", count, out.wide.size()));
    out.is_wide = true;
    return out;
}

TextColumn char_labels(const CharUnits& units, std::size_t rows, std::size_t width) {
    return units.is_wide ? char_matrix_labels(units.wide.data(), rows, width) : char_matrix_labels(units.bytes.data(), rows, width);
}

// A top-level variable: where its element is, and its header.
struct Variable {
    std::uint64_t offset = 0;  // of its tag
    std::uint64_t bytes = 0;   // after its tag
    bool compressed = false;
    ArrayHeader header;
};

class Mat5File {
public:
    explicit Mat5File(const std::filesystem::path& path) : file_(path.string()), in_(path, std::ios::binary) {}

    FileColumns read(const ColumnChoice& choose);

private:
    [[noreturn]] void refuse(const std::string& field, const std::string& message) const { throw InputError(file_, 0, field, message); }
    std::vector<std::uint8_t> read_bytes(std::uint64_t offset, std::size_t n);
    std::vector<std::uint8_t> inflated(const Variable& v, std::size_t limit, bool whole, const std::string& field,
                                       std::string* damage_found = nullptr);
    std::vector<std::uint8_t> element_data(const Variable& v, std::size_t limit, bool whole, const std::string& field,
                                           std::string* damage_found = nullptr);
    std::vector<Variable> list_variables();
    FileColumn column_of(Bytes& body, const ArrayHeader& h, const std::string& field) const;
    TextColumn cell_labels(Bytes& body, const ArrayHeader& h, const std::string& field) const;

    std::string file_;
    std::ifstream in_;
    std::uint64_t size_ = 0;
    bool big_endian_ = false;
};

std::vector<std::uint8_t> Mat5File::read_bytes(std::uint64_t offset, std::size_t n) {
    std::vector<std::uint8_t> out(n);
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(reinterpret_cast<char*>(out.data()), static_cast<std::streamsize>(n));
    if (static_cast<std::size_t>(in_.gcount()) != n) refuse("", fmt::format("reading {} bytes at byte {} failed: the file changed while it was read?", n, offset));
    return out;
}

// The decompressed bytes of a compressed variable: the first `limit` of them, or (`whole`) all of
// them, refused beyond `limit`. Inflating to the end makes zlib check the stream's Adler-32 sum.
std::vector<std::uint8_t> Mat5File::inflated(const Variable& v, std::size_t limit, bool whole, const std::string& field,
                                             std::string* damage_found) {
    z_stream z{};
    if (inflateInit(&z) != Z_OK) refuse(field, "zlib cannot start");
    struct End {
        z_stream& z;
        ~End() { inflateEnd(&z); }
    } end{z};
    std::vector<std::uint8_t> out, input;
    std::uint64_t read = 0;
    const std::uint64_t start = v.offset + 8;
    int status = Z_OK;
    while (status != Z_STREAM_END) {
        if (z.avail_in == 0) {
            if (read == v.bytes)
                refuse(field, fmt::format("its compressed data ends before the end of the stream ({} bytes at byte {}): the file is cut short "
                                          "or damaged", v.bytes, v.offset));
            const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(v.bytes - read, 1 << 16));
            input = read_bytes(start + read, n);
            read += n;
            z.next_in = input.data();
            z.avail_in = static_cast<uInt>(n);
        }
        if (out.size() == limit) {
            if (!whole) return out;
            refuse(field, fmt::format("decompressed, the variable is larger than {} bytes, more than a log of {} rows takes "
                                      "(damaged, or not a measurement)", limit, max_measurement_rows));
        }
        const std::size_t have = out.size();
        out.resize(std::min(limit, std::max<std::size_t>(have * 2, 1 << 16)));
        z.next_out = out.data() + have;
        z.avail_out = static_cast<uInt>(out.size() - have);
        status = inflate(&z, Z_NO_FLUSH);
        out.resize(out.size() - z.avail_out);
        if (status == Z_NEED_DICT || status == Z_DATA_ERROR || status == Z_MEM_ERROR || status == Z_STREAM_ERROR) {
            const std::string damage =
                fmt::format("its compressed data is damaged (zlib: {}); the file is damaged", z.msg ? z.msg : zError(status));
            // What was inflated may name the variable; the damage may be in the name itself, so
            // the variable is refused, never passed over as one not used.
            if (!whole && damage_found) {
                *damage_found = damage;
                return out;
            }
            refuse(field, damage);
        }
        if (status == Z_BUF_ERROR && z.avail_in != 0 && z.avail_out != 0) refuse(field, "its compressed data is damaged (zlib makes no progress)");
    }
    return out;
}

// The bytes of a variable's miMATRIX element, tag included: read as they are, or decompressed.
std::vector<std::uint8_t> Mat5File::element_data(const Variable& v, std::size_t limit, bool whole, const std::string& field,
                                                 std::string* damage_found) {
    if (v.compressed) return inflated(v, limit, whole, field, damage_found);
    if (whole && v.bytes + 8 > limit)
        refuse(field, fmt::format("a variable of {} bytes, more than a log of {} rows takes (damaged, or not a measurement)", v.bytes,
                                  max_measurement_rows));
    return read_bytes(v.offset, static_cast<std::size_t>(std::min<std::uint64_t>(v.bytes + 8, limit)));
}

std::vector<Variable> Mat5File::list_variables() {
    if (!in_) refuse("", "cannot open the MAT file");
    std::error_code ec;
    size_ = std::filesystem::file_size(file_, ec);
    if (ec || size_ < header_bytes)
        refuse("", fmt::format("a MAT file cut short: {} bytes, less than a MAT file's {}-byte header", size_, header_bytes));
    const auto header = read_bytes(0, header_bytes);
    if (header[126] == 'I' && header[127] == 'M') big_endian_ = false;
    else if (header[126] == 'M' && header[127] == 'I') big_endian_ = true;
    else refuse("", "a MAT v5 header without its byte-order mark (bytes 126-127 are neither 'IM' nor 'MI'): the file is damaged");

    std::vector<Variable> variables;
    for (std::uint64_t offset = header_bytes; offset < size_;) {
        const std::string where = fmt::format("variable {} (at byte {})", variables.size() + 1, offset);
        if (size_ - offset < 8) refuse("", fmt::format("{}: {} bytes where a variable's 8-byte tag belongs: the file is cut short or damaged", where, size_ - offset));
        if (variables.size() == max_file_variables)
            refuse("", fmt::format("more than {} variables; mhbench reads logs of at most that many variables", max_file_variables));
        const auto tag = read_bytes(offset, 8);
        Bytes b(tag, big_endian_);
        Variable v;
        v.offset = offset;
        const std::uint32_t type = b.u32();
        v.bytes = b.u32();
        if (type != mi_matrix && type != mi_compressed)
            refuse("", fmt::format("{}: an element of type {} where a variable belongs: the file is damaged", where, type));
        if (v.bytes > size_ - offset - 8)
            refuse("", fmt::format("{} declares {} bytes but the file ends {} bytes after its tag: the file is cut short", where, v.bytes,
                                   size_ - offset - 8));
        v.compressed = type == mi_compressed;
        offset += 8 + v.bytes;
        if (v.bytes == 0) continue;  // an empty element names nothing
        std::string damage;
        const auto start = element_data(v, array_header_bytes, false, where, &damage);
        try {
            // Only the element's start is at hand: its tag, then as much of its data as was read.
            Bytes element(start, big_endian_);
            if (element.u32() != mi_matrix) throw Damage("its compressed data is not a variable");
            const std::uint32_t matrix_bytes = element.u32();
            if (matrix_bytes == 0) continue;
            Bytes body(element.take(std::min<std::size_t>(matrix_bytes, element.left())), big_endian_);
            v.header = array_header(body);
        } catch (const Damage& e) {
            refuse("", fmt::format("{}: {}", where, damage.empty() ? "damaged: " + std::string(e.what()) : damage));
        }
        if (!damage.empty()) refuse("", fmt::format("{}, named '{}' as far as it can be read: {}", where, printable_field(v.header.name), damage));
        variables.push_back(std::move(v));
    }
    return variables;
}

FileColumn Mat5File::column_of(Bytes& body, const ArrayHeader& h, const std::string& field) const {
    FileColumn column;
    const std::uint64_t n = h.elements();
    if (h.array_class >= mx_double && h.array_class <= mx_uint64) {
        const auto real = body.element();
        const std::size_t size = type_size(real.type);
        if (size == 0 || real.type == mi_utf8 || real.type == mi_utf16 || real.type == mi_utf32)
            throw Damage(fmt::format("numbers stored as data type {}", real.type));
        if (real.data.size() != n * size) throw Damage(fmt::format("{} values declared, {} bytes of {}-byte values held", n, real.data.size(), size));
        column.numbers.resize(static_cast<Eigen::Index>(n));
        for (std::size_t k = 0; k < n; ++k) column.numbers[static_cast<Eigen::Index>(k)] = number_at(body, real.data, real.type, k);
        return column;
    }
    if (h.array_class == mx_char) {
        const auto data = body.element();
        column.labels = char_labels(char_units(body, data, n), h.dims[0], h.dims[1]);
        return column;
    }
    column.labels = cell_labels(body, h, field);
    return column;
}

// The labels of a cell array of char row vectors, one cell per row.
TextColumn Mat5File::cell_labels(Bytes& body, const ArrayHeader& h, const std::string& field) const {
    TextColumn out;
    const std::uint64_t n = h.elements();
    out.rows.resize(static_cast<Eigen::Index>(n));
    for (std::uint64_t r = 0; r < n; ++r) {
        auto refuse_row = [&](const std::string& what) { refuse(field, fmt::format("row {}: {}", r + 1, what)); };
        const auto cell = body.element();
        if (cell.type != mi_matrix) throw Damage(fmt::format("cell {} is not an array", r + 1));
        std::string text;
        if (!cell.data.empty()) {
            Bytes b(cell.data, body.big_endian());
            const ArrayHeader c = array_header(b);
            const std::uint64_t count = c.elements();
            if (c.array_class != mx_char && count > 0) refuse_row(fmt::format("the cell holds a {}, not text", class_name(c.array_class)));
            if (count > 0) {
                if (c.dims.size() != 2 || c.dims[0] != 1) refuse_row(fmt::format("the cell holds a {} char matrix, not one line of text", c.shape()));
                if (c.dims[1] > max_label_bytes)
                    refuse_row(fmt::format("a label of {} characters; mhbench reads labels of at most {} characters", c.dims[1], max_label_bytes));
                const auto data = b.element();
                text = char_labels(char_units(b, data, count), 1, c.dims[1]).texts[0];
            }
        }
        out.rows[static_cast<Eigen::Index>(r)] = out.index_of(text);
    }
    return out;
}

// Why a variable with this header cannot feed a column, or "" when it can.
std::string unusable(const ArrayHeader& h) {
    const bool numeric = h.array_class >= mx_double && h.array_class <= mx_uint64;
    if (numeric && h.complex) return fmt::format("a complex {} array; mhbench reads real numbers", h.shape());
    if (numeric || h.array_class == mx_cell) {
        if (!h.vector()) return fmt::format("a {} {}, not a vector", h.shape(), numeric ? "matrix" : "cell array");
        return "";
    }
    if (h.array_class == mx_char) {
        if (h.dims.size() != 2) return fmt::format("a {} char array in an unsupported shape", h.shape());
        if (h.dims[1] > max_label_bytes)
            return fmt::format("a char matrix {} characters wide; mhbench reads labels of at most {} characters", h.dims[1], max_label_bytes);
        return "";
    }
    return fmt::format("a {} {}, not a vector", h.shape(), class_name(h.array_class));
}

// The rows a usable variable declares: its elements, or a char matrix's rows.
std::uint64_t declared_rows(const ArrayHeader& h) { return h.array_class == mx_char ? h.dims[0] : h.elements(); }

// Refuses a variable that cannot feed a column, else checks the rows it declares against the others.
void check_used(const std::string& file, const ArrayHeader& h, const std::string& field, DeclaredRows& rows) {
    if (h.array_class == 0 || h.elements() == 0) throw InputError(file, 0, field, "empty: no rows");
    if (const auto why = unusable(h); !why.empty()) throw InputError(file, 0, field, why);
    rows.check(field, declared_rows(h));
}

// The most bytes a usable variable may take, its tag included: a numeric vector at most 8 bytes a
// row (double, the widest class) beside its header; text has no such bound.
std::size_t most_bytes(const ArrayHeader& h) {
    const bool numeric = h.array_class >= mx_double && h.array_class <= mx_uint64;
    return numeric ? array_header_bytes + 64 + static_cast<std::size_t>(8 * h.elements()) : max_variable_bytes;
}

FileColumns Mat5File::read(const ColumnChoice& choose) {
    const auto variables = list_variables();
    FileColumns out;
    if (variables.empty()) refuse("", "the MAT file holds no variables");
    const bool one_struct = variables.size() == 1 && variables[0].header.array_class == mx_struct;
    DeclaredRows rows(file_);

    if (one_struct) {
        const Variable& s = variables[0];
        const std::string field = printable_field(s.header.name);
        if (s.header.elements() != 1)
            refuse(field, fmt::format("a {} struct array; mhbench reads the fields of a single (1x1) struct", s.header.shape()));
        const auto data = element_data(s, max_variable_bytes, true, field);
        try {
            Bytes element(data, big_endian_);
            const auto matrix = element.element();
            Bytes body(matrix.data, big_endian_);
            array_header(body);
            const auto length = body.element();
            if (length.type != mi_int32 || length.data.size() != 4) throw Damage("no field-name length in the struct");
            const auto width = static_cast<std::size_t>(body.unsigned_value(length.data));
            const auto names_element = body.element();
            if (width == 0 || width > max_label_bytes || names_element.data.size() % width != 0) throw Damage("field names of a length that does not divide their bytes");
            std::vector<std::string> names;
            for (std::size_t k = 0; k < names_element.data.size(); k += width) {
                const auto name = names_element.data.subspan(k, width);
                names.emplace_back(name.begin(), std::find(name.begin(), name.end(), std::uint8_t{0}));
            }
            // Each field is a nameless array element; its header comes first, its data after.
            std::vector<std::pair<ArrayHeader, Bytes>> fields;
            for (std::size_t f = 0; f < names.size(); ++f) {
                const auto e = body.element();
                if (e.type != mi_matrix) throw Damage(fmt::format("field '{}' is not an array", printable_field(names[f])));
                Bytes b(e.data, big_endian_);
                ArrayHeader h;
                if (!e.data.empty()) h = array_header(b);
                else h.array_class = 0;
                h.name = names[f];
                fields.emplace_back(std::move(h), b);
            }
            const auto bound = choose(names);
            std::vector<std::size_t> used;
            for (std::size_t f = 0; f < fields.size(); ++f) {
                if (bound[f].empty()) {
                    out.unused.push_back(names[f]);
                    continue;
                }
                check_used(file_, fields[f].first, variable_field(names[f], bound[f]), rows);
                used.push_back(f);
            }
            for (const auto f : used) {
                const std::string f_field = variable_field(names[f], bound[f]);
                try {
                    auto column = column_of(fields[f].second, fields[f].first, f_field);
                    column.name = names[f];
                    column.column = bound[f];
                    out.columns.push_back(std::move(column));
                } catch (const Damage& e) {
                    refuse(f_field, fmt::format("damaged: {}", e.what()));
                }
            }
        } catch (const Damage& e) {
            refuse(field, fmt::format("damaged: {}", e.what()));
        }
        return out;
    }

    std::vector<std::string> names;
    for (const auto& v : variables) names.push_back(v.header.name);
    // A struct beside other variables is not a column; it keeps its name out of the choice so that
    // a map naming it is told it is absent.
    std::vector<std::string> listed;
    std::vector<std::size_t> listed_index;
    for (std::size_t k = 0; k < variables.size(); ++k) {
        if (variables[k].header.array_class == mx_struct) {
            out.notes.push_back(fmt::format("{}: struct '{}' was ignored: the columns are the top-level variables (a struct's fields are the "
                                            "columns only when the file holds that one struct and nothing else)",
                                            file_, printable_field(names[k])));
            continue;
        }
        listed.push_back(names[k]);
        listed_index.push_back(k);
    }
    const auto bound = choose(listed);
    std::vector<std::pair<std::size_t, std::string>> used;  // variable, column
    for (std::size_t j = 0; j < listed.size(); ++j) {
        if (bound[j].empty()) {
            out.unused.push_back(listed[j]);
            continue;
        }
        const auto& h = variables[listed_index[j]].header;
        check_used(file_, h, variable_field(listed[j], bound[j]), rows);
        used.emplace_back(listed_index[j], bound[j]);
    }
    for (const auto& [k, column_name] : used) {
        const Variable& v = variables[k];
        const std::string field = variable_field(v.header.name, column_name);
        const auto data = element_data(v, most_bytes(v.header), true, field);
        try {
            Bytes element(data, big_endian_);
            const auto matrix = element.element();
            if (matrix.type != mi_matrix) throw Damage("not a variable");
            Bytes body(matrix.data, big_endian_);
            const ArrayHeader h = array_header(body);
            if (h.dims != v.header.dims || h.array_class != v.header.array_class) throw Damage("its header changed while it was read");
            auto column = column_of(body, h, field);
            column.name = v.header.name;
            column.column = column_name;
            out.columns.push_back(std::move(column));
        } catch (const Damage& e) {
            refuse(field, fmt::format("damaged: {}", e.what()));
        }
    }
    return out;
}

}  // namespace

FileColumns read_mat5_columns(const std::filesystem::path& path, const ColumnChoice& choose) { return Mat5File(path).read(choose); }

}  // namespace mhb::pmsm

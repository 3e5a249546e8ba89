// HDF5 files, and MAT v7.3 files (HDF5 with MATLAB's conventions), through the HDF5 C library. Built
// as a library of its own, loaded by the first command that reads such a file (hdf5_reader()).
// The file's links are listed in one pass; only the datasets that feed a column are opened, and
// each is checked (layout, storage, class, shape, rows, string sizes) before its data is read.
#include <algorithm>
#include <cstring>
#include <utility>

#include <fmt/format.h>
#include <hdf5.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/column_map.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

namespace mhb::pmsm {
namespace {

// An HDF5 identifier, closed with its own close function when it goes out of scope.
class Handle {
public:
    Handle() = default;
    Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
    Handle(Handle&& other) noexcept : id_(std::exchange(other.id_, -1)), close_(other.close_) {}
    Handle& operator=(Handle&& other) noexcept {
        std::swap(id_, other.id_);
        std::swap(close_, other.close_);
        return *this;
    }
    Handle(const Handle&) = delete;
    Handle& operator=(const Handle&) = delete;
    ~Handle() {
        if (id_ >= 0 && close_) close_(id_);
    }
    hid_t get() const { return id_; }

private:
    hid_t id_ = -1;
    herr_t (*close_)(hid_t) = nullptr;
};

herr_t keep_description(unsigned, const H5E_error2_t* error, void* out) {
    if (error->desc && *error->desc) static_cast<std::vector<std::string>*>(out)->emplace_back(error->desc);
    return 0;
}

// The library's reason for its last failure: the innermost description on its error stack, where
// the damage was found ("truncated file: eof = 4096, ..."), not the API call that reported it.
std::string library_reason() {
    std::vector<std::string> descriptions;
    H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, keep_description, &descriptions);
    H5Eclear2(H5E_DEFAULT);
    if (descriptions.empty()) return "no reason given";
    // The library's text may quote bytes of the file; nothing a terminal would act on is passed on.
    std::string reason = descriptions.back().substr(0, 200);
    for (char& c : reason)
        if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7F) c = '?';
    return reason;
}

struct Link {
    std::string name;
    H5L_type_t type;
    H5O_type_t object = H5O_TYPE_UNKNOWN;
};

herr_t keep_link(hid_t, const char* name, const H5L_info_t* info, void* out) {
    auto& links = *static_cast<std::vector<Link>*>(out);
    if (links.size() >= max_file_variables) return 1;  // stops the iteration; refused by the caller
    links.push_back({name, info->type});
    return 0;
}

const char* class_name(H5T_class_t c) {
    switch (c) {
        case H5T_COMPOUND: return "compound (table-like)";
        case H5T_ENUM: return "enum";
        case H5T_ARRAY: return "array-typed";
        case H5T_VLEN: return "variable-length";
        case H5T_REFERENCE: return "reference";
        case H5T_OPAQUE: return "opaque";
        case H5T_BITFIELD: return "bitfield";
        case H5T_TIME: return "time";
        default: return "unsupported";
    }
}

// The most characters a v7.3 char matrix of labels may hold: 5 million labels of 50 characters.
constexpr hsize_t max_char_matrix_units = hsize_t{1} << 28;

std::string shape(const std::vector<hsize_t>& dims) {
    if (dims.empty()) return "scalar";
    std::string out;
    for (std::size_t d = 0; d < dims.size(); ++d) out += (d ? "x" : "") + std::to_string(dims[d]);
    return out;
}

bool is_vector(const std::vector<hsize_t>& dims) {
    return dims.size() == 1 || (dims.size() == 2 && (dims[0] == 1 || dims[1] == 1));
}

// Called where a path would leave the file through an external link: the traversal fails. Without
// it, a soft link to an external link would be followed into any file, a FIFO included.
herr_t refuse_external_link(const char*, const char*, const char*, const char*, unsigned*, hid_t, void*) { return -1; }

// Access properties for `kind` (links, datasets, groups) under which no external link is followed.
Handle closed_to_external_links(hid_t kind) {
    Handle access(H5Pcreate(kind), H5Pclose);
    H5Pset_elink_cb(access.get(), refuse_external_link, nullptr);
    return access;
}

// The reading of one file: its name for messages, and the layout it is read in.
class Hdf5File {
public:
    Hdf5File(const std::filesystem::path& path, Hdf5Layout layout)
        : path_(path), file_(path.string()), layout_(layout), link_access_(closed_to_external_links(H5P_LINK_ACCESS)),
          dataset_access_(closed_to_external_links(H5P_DATASET_ACCESS)), group_access_(closed_to_external_links(H5P_GROUP_ACCESS)) {}

    FileColumns read(const ColumnChoice& choose);

private:
    enum class Kind { numbers, strings, matlab_chars, matlab_cells };
    // A used dataset, open and checked, its data not yet read.
    struct Planned {
        std::string name, column, field;
        Handle dataset, space, type;
        std::vector<hsize_t> dims;
        std::uint64_t rows = 0;
        Kind kind = Kind::numbers;
    };

    [[noreturn]] void refuse(const std::string& field, const std::string& message) const {
        throw InputError(file_, 0, field, message);
    }
    // `id`, or a refusal saying what failed and the library's reason.
    hid_t checked(hid_t id, const std::string& field, const std::string& what) const {
        if (id < 0) refuse(field, fmt::format("{}: {} (the file is damaged or truncated)", what, library_reason()));
        return id;
    }
    Handle open_file() const;
    std::vector<Link> links_of(hid_t group, const std::string& where) const;
    std::string matlab_class(hid_t object) const;
    bool matlab_attribute_set(hid_t object, const char* name) const;
    Planned plan(hid_t group, const Link& link, const std::string& column, DeclaredRows& rows) const;
    FileColumn read_planned(Planned& p) const;
    TextColumn read_strings(Planned& p) const;
    TextColumn read_matlab_chars(Planned& p) const;
    TextColumn read_matlab_cells(Planned& p) const;
    std::string matlab_text(hid_t object, const std::string& field, std::uint64_t row) const;
    void check_compact_size(hid_t dataset, hid_t space, hid_t type, const std::string& field) const;

    std::filesystem::path path_;
    std::string file_;
    Hdf5Layout layout_;
    Handle link_access_, dataset_access_, group_access_;
};

Handle Hdf5File::open_file() const {
    std::error_code ec;
    const auto size = std::filesystem::file_size(path_, ec);
    const char* what = layout_ == Hdf5Layout::matlab ? "MAT v7.3 file" : "HDF5 file";
    // The smallest HDF5 file (signature and superblock) is 96 bytes, after a v7.3 file's 512-byte header.
    const std::uintmax_t least = layout_ == Hdf5Layout::matlab ? 512 + 96 : 96;
    if (!ec && size < least)
        refuse("", fmt::format("a {} cut short: {} bytes, less than the smallest such file ({} bytes)", what, size, least));
    const Handle access(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    // Every object the file held is closed with the file, so no identifier outlives a refusal.
    H5Pset_fclose_degree(access.get(), H5F_CLOSE_STRONG);
    // The metadata cache counts an object header at its size on disk but keeps it decoded, several
    // times larger: at its default 32 MB, the 100 000 cells of a v7.3 cell array made it hold
    // 590 MB. Each header is read once here, so a small cache costs no time.
    H5AC_cache_config_t cache;
    cache.version = H5AC__CURR_CACHE_CONFIG_VERSION;
    if (H5Pget_mdc_config(access.get(), &cache) >= 0) {
        cache.set_initial_size = true;
        cache.initial_size = std::size_t{1} << 20;
        cache.min_size = std::size_t{1} << 20;
        cache.max_size = std::size_t{2} << 20;
        H5Pset_mdc_config(access.get(), &cache);
    }
    Handle file(H5Fopen(file_.c_str(), H5F_ACC_RDONLY, access.get()), H5Fclose);
    if (file.get() < 0)
        refuse("", fmt::format("not a readable {}: {}; the file is damaged or truncated (save or copy it again)", what, library_reason()));
    return file;
}

std::vector<Link> Hdf5File::links_of(hid_t group, const std::string& where) const {
    // One iteration over the group's index. Asking for the k-th name instead costs k steps in
    // the symbol tables MATLAB and most writers use, which made 40 000 datasets take 44 s.
    std::vector<Link> links;
    hsize_t index = 0;
    const herr_t status = H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, &index, keep_link, &links);
    if (status < 0) refuse(where, fmt::format("cannot list the {}: {} (the file is damaged or truncated)", where.empty() ? "root group" : "group", library_reason()));
    if (status > 0) refuse(where, fmt::format("holds more than {} links; mhbench reads logs of at most that many variables", max_file_variables));
    for (auto& link : links) {
        if (link.type != H5L_TYPE_HARD && link.type != H5L_TYPE_SOFT) continue;
        H5O_info_t info;
        // A soft link that leads nowhere is not an object: it stays "unknown" and is passed over.
        if (H5Oget_info_by_name2(group, link.name.c_str(), &info, H5O_INFO_BASIC, link_access_.get()) >= 0) link.object = info.type;
        else H5Eclear2(H5E_DEFAULT);
    }
    return links;
}

// The MATLAB class a v7.3 file gives an object ("double", "char", "cell", ...), or "" without one.
std::string Hdf5File::matlab_class(hid_t object) const {
    if (H5Aexists(object, "MATLAB_class") <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return "";
    }
    const Handle attribute(H5Aopen(object, "MATLAB_class", H5P_DEFAULT), H5Aclose);
    if (attribute.get() < 0) return "";
    const Handle stored(H5Aget_type(attribute.get()), H5Tclose);
    if (H5Tget_class(stored.get()) != H5T_STRING || H5Tis_variable_str(stored.get()) > 0) return "";
    const std::size_t width = H5Tget_size(stored.get());
    if (width == 0 || width > 64) return "";
    const Handle memory(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(memory.get(), width);
    std::string text(width, '\0');
    if (H5Aread(attribute.get(), memory.get(), text.data()) < 0) {
        H5Eclear2(H5E_DEFAULT);
        return "";
    }
    text.resize(std::strlen(text.c_str()));
    return text;
}

// Whether a v7.3 file marks an object with a nonzero integer attribute (MATLAB_empty, MATLAB_sparse).
bool Hdf5File::matlab_attribute_set(hid_t object, const char* name) const {
    if (H5Aexists(object, name) <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
    }
    const Handle attribute(H5Aopen(object, name, H5P_DEFAULT), H5Aclose);
    const Handle space(H5Aget_space(attribute.get()), H5Sclose);
    if (H5Sget_simple_extent_npoints(space.get()) != 1) return true;
    // The library converts through a buffer of the stored type's size, which a damaged file may
    // declare as gigabytes (found by fuzz_mat73); MATLAB writes these flags as 1-byte to 8-byte integers.
    const Handle stored(H5Aget_type(attribute.get()), H5Tclose);
    if (H5Tget_class(stored.get()) != H5T_INTEGER || H5Tget_size(stored.get()) == 0 || H5Tget_size(stored.get()) > 8) return true;
    unsigned long long value = 1;
    if (H5Aread(attribute.get(), H5T_NATIVE_ULLONG, &value) < 0) H5Eclear2(H5E_DEFAULT);
    return value != 0;
}

// Compact data lives in the object header, in a block of the size the header declares; libhdf5
// 1.10.8 copies what the shape and type ask for out of it without comparing the two (fuzz_hdf5 and
// fuzz_mat73: H5D__compact_readvv read past the block). The type's size is its size in memory, which
// for variable-length strings is less than the file's, so no valid file is refused.
void Hdf5File::check_compact_size(hid_t dataset, hid_t space, hid_t type, const std::string& field) const {
    const hssize_t points = H5Sget_simple_extent_npoints(space);
    const hsize_t needed = static_cast<hsize_t>(std::max<hssize_t>(points, 0)) * H5Tget_size(type);
    const hsize_t held = H5Dget_storage_size(dataset);
    if (held < needed) refuse(field, fmt::format("compact data of {} bytes where its shape and type take {} (the file is damaged)", held, needed));
}

Hdf5File::Planned Hdf5File::plan(hid_t group, const Link& link, const std::string& column, DeclaredRows& rows) const {
    Planned p;
    p.name = link.name;
    p.column = column;
    p.field = variable_field(link.name, column);
    if (link.type == H5L_TYPE_EXTERNAL)
        refuse(p.field, "an external link into another file; mhbench reads only what this file holds (copy the data into it)");
    if (link.object != H5O_TYPE_DATASET) refuse(p.field, "not a dataset (a group, or a named type)");
    p.dataset = Handle(checked(H5Dopen2(group, link.name.c_str(), dataset_access_.get()), p.field, "cannot open the dataset"), H5Dclose);
    const hid_t dataset = p.dataset.get();
    bool compact = false;
    {
        // Data kept outside the file could be anything, a FIFO included: it is never read.
        const Handle creation(checked(H5Dget_create_plist(dataset), p.field, "cannot read how the dataset is stored"), H5Pclose);
        compact = H5Pget_layout(creation.get()) == H5D_COMPACT;
        if (H5Pget_layout(creation.get()) == H5D_VIRTUAL)
            refuse(p.field, "a virtual dataset, whose data lives in other files; mhbench reads only what this file holds");
        if (H5Pget_external_count(creation.get()) > 0)
            refuse(p.field, "its data is stored in external files; mhbench reads only what this file holds");
    }
    p.space = Handle(checked(H5Dget_space(dataset), p.field, "cannot read the dataset's shape"), H5Sclose);
    const int rank = H5Sget_simple_extent_ndims(p.space.get());
    if (rank < 0) refuse(p.field, fmt::format("cannot read the dataset's shape: {}", library_reason()));
    p.dims.resize(static_cast<std::size_t>(rank));
    if (rank > 0) H5Sget_simple_extent_dims(p.space.get(), p.dims.data(), nullptr);
    p.type = Handle(checked(H5Dget_type(dataset), p.field, "cannot read the dataset's type"), H5Tclose);
    const H5T_class_t type_class = H5Tget_class(p.type.get());

    std::string matlab;
    if (layout_ == Hdf5Layout::matlab) {
        matlab = matlab_class(dataset);
        if (matlab_attribute_set(dataset, "MATLAB_empty")) refuse(p.field, "empty: no rows");
        if (matlab_attribute_set(dataset, "MATLAB_sparse")) refuse(p.field, "a sparse matrix; mhbench reads full vectors");
    }
    if (matlab == "char") {
        // MATLAB's rows x width char matrix is stored as HDF5 dims {width, rows}.
        if (p.dims.size() != 2 || (type_class != H5T_INTEGER) || H5Tget_size(p.type.get()) > 2)
            refuse(p.field, fmt::format("a {} char array in an unsupported encoding or shape", shape(p.dims)));
        if (p.dims[0] > max_label_bytes)
            refuse(p.field, fmt::format("a char matrix {} characters wide; mhbench reads labels of at most {} characters", p.dims[0], max_label_bytes));
        // Each label is at most max_label_bytes wide, but rows times width could still ask for
        // tens of GB from a file whose compressed chunks declare them.
        if (p.dims[0] * p.dims[1] > max_char_matrix_units)
            refuse(p.field, fmt::format("a {} char matrix, more than the {} characters mhbench reads in one", shape(p.dims), max_char_matrix_units));
        p.kind = Kind::matlab_chars;
        p.rows = p.dims[1];
    } else if (matlab == "cell") {
        if (type_class != H5T_REFERENCE || !is_vector(p.dims)) refuse(p.field, fmt::format("a {} cell array, not a vector", shape(p.dims)));
        if (H5Tequal(p.type.get(), H5T_STD_REF_OBJ) <= 0) refuse(p.field, "a cell array whose cells are not object references (the file is damaged)");
        p.kind = Kind::matlab_cells;
    } else if (type_class == H5T_INTEGER || type_class == H5T_FLOAT) {
        if (!is_vector(p.dims))
            refuse(p.field, fmt::format("a {} {}, not a vector", shape(p.dims), layout_ == Hdf5Layout::matlab ? "matrix" : "dataset"));
        // The library converts to double through a buffer of at least one stored number, whose size a
        // damaged type declares: fuzz_mat73 found numbers of 1.6 GB and 4 GB each, allocated by H5Dread.
        const std::size_t number_bytes = H5Tget_size(p.type.get());
        if (number_bytes == 0 || number_bytes > 8)
            refuse(p.field, fmt::format("numbers of {} bytes each; mhbench reads integers and floats of 1 to 8 bytes (the file is damaged?)",
                                        number_bytes));
        // The significant bits must lie inside the number: libhdf5 1.10.8 converts a 2-byte integer
        // whose bits start at bit 4096 by reading far past it (fuzz_hdf5: a bus error in H5T__bit_copy).
        const int bit_offset = H5Tget_offset(p.type.get());
        const std::size_t bits = H5Tget_precision(p.type.get());
        if (bit_offset < 0 || bits == 0 || static_cast<std::size_t>(bit_offset) + bits > 8 * number_bytes)
            refuse(p.field, fmt::format("numbers of {} bytes whose {} significant bits start at bit {} (the file is damaged)", number_bytes,
                                        bits, bit_offset));
        p.kind = Kind::numbers;
    } else if (type_class == H5T_STRING && layout_ == Hdf5Layout::plain) {
        if (!is_vector(p.dims)) refuse(p.field, fmt::format("a {} dataset, not a vector", shape(p.dims)));
        p.kind = Kind::strings;
    } else if (layout_ == Hdf5Layout::matlab) {
        refuse(p.field, type_class == H5T_COMPOUND ? std::string("complex numbers; mhbench reads real numbers")
                                                   : fmt::format("a MATLAB {} variable; mhbench reads numeric vectors, and text in segment",
                                                                 matlab.empty() ? "unknown" : printable_field(matlab)));
    } else {
        refuse(p.field, fmt::format("a dataset of {} type; mhbench reads numbers and strings", class_name(type_class)));
    }
    if (p.kind != Kind::matlab_chars)
        p.rows = p.dims.empty() ? 1 : p.dims.size() == 1 ? p.dims[0] : p.dims[0] * p.dims[1];
    rows.check(p.field, p.rows);
    if (p.kind == Kind::strings && H5Tis_variable_str(p.type.get()) <= 0) {
        // 0 is also the library's answer for a type it cannot read; read_strings divides by the
        // width (fuzz_hdf5: a division by zero there).
        const std::size_t width = H5Tget_size(p.type.get());
        if (width == 0) refuse(p.field, "fixed-length strings of 0 bytes (the file is damaged)");
        if (width > max_label_bytes)
            refuse(p.field, fmt::format("fixed-length strings of {} bytes; mhbench reads labels of at most {} bytes", width, max_label_bytes));
    }
    if (compact) check_compact_size(dataset, p.space.get(), p.type.get(), p.field);
    // A dataset whose storage was never (fully) written reads as its fill value: zeros that the
    // file never held. Compact and contiguous storage is allocated whole or not at all.
    H5D_space_status_t status = H5D_SPACE_STATUS_ERROR;
    if (H5Dget_space_status(dataset, &status) < 0) H5Eclear2(H5E_DEFAULT);
    if (p.rows > 0 && status != H5D_SPACE_STATUS_ALLOCATED)
        refuse(p.field, fmt::format("declares {} rows but holds data for {} of them (never written, or the file is damaged)", p.rows,
                                    status == H5D_SPACE_STATUS_PART_ALLOCATED ? "only some" : "none"));
    return p;
}

TextColumn Hdf5File::read_strings(Planned& p) const {
    // Labels are read a slab at a time: the library allocates every variable-length string on its
    // own, and a million of them at once would cost more than all the numeric columns. Fixed-length
    // strings take width bytes a row, so their slab holds as many rows as fit in 16 MB.
    const hid_t dataset = p.dataset.get();
    const bool variable = H5Tis_variable_str(p.type.get()) > 0;
    const std::size_t width = variable ? sizeof(char*) : H5Tget_size(p.type.get());
    // Checked when planned, but the library may answer differently now, after reading other
    // columns of a damaged file (fuzz_hdf5: 0 here, then a fault inside malloc).
    if (width == 0) refuse(p.field, "fixed-length strings of 0 bytes (the file is damaged)");
    const Handle memory(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(memory.get(), variable ? H5T_VARIABLE : width);
    // UTF-8 stays UTF-8 (h5py writes its strings so); the library converts nothing between sets.
    H5Tset_cset(memory.get(), H5Tget_cset(p.type.get()));
    const std::size_t axis = p.dims.size() == 2 && p.dims[0] == 1 ? 1 : 0;
    const hsize_t slab = std::max<hsize_t>(1, std::min<hsize_t>(hsize_t{1} << 16, (std::size_t{16} << 20) / width));
    std::vector<char> buffer(static_cast<std::size_t>(std::min<hsize_t>(slab, p.rows)) * width);
    TextColumn out;
    out.rows.resize(static_cast<Eigen::Index>(p.rows));
    for (hsize_t start = 0; start < p.rows; start += slab) {
        std::vector<hsize_t> offset(p.dims.size(), 0), count = p.dims;
        offset[axis] = start;
        count[axis] = std::min<hsize_t>(slab, p.rows - start);
        const Handle in_file(H5Scopy(p.space.get()), H5Sclose);
        H5Sselect_hyperslab(in_file.get(), H5S_SELECT_SET, offset.data(), nullptr, count.data(), nullptr);
        const Handle in_memory(H5Screate_simple(1, &count[axis], nullptr), H5Sclose);
        const std::string rows = fmt::format("rows {} to {}", start + 1, start + count[axis]);
        if (variable) {
            // The bytes the slab's strings need, from their lengths in the file, before any is read.
            hsize_t bytes = 0;
            checked(H5Dvlen_get_buf_size(dataset, memory.get(), in_file.get(), &bytes), p.field, "cannot read the labels' sizes in " + rows);
            if (bytes > count[axis] * (max_label_bytes + 1))
                refuse(p.field, fmt::format("{}: labels of {} bytes in all; mhbench reads labels of at most {} bytes", rows, bytes, max_label_bytes));
        }
        checked(H5Dread(dataset, memory.get(), in_memory.get(), in_file.get(), H5P_DEFAULT, buffer.data()), p.field, "cannot read " + rows);
        for (hsize_t k = 0; k < count[axis]; ++k) {
            std::string_view text;
            if (variable) {
                const char* s = reinterpret_cast<char**>(buffer.data())[k];
                text = s ? std::string_view(s) : std::string_view();
            } else {
                text = std::string_view(buffer.data() + k * width, width);
                while (!text.empty() && (text.back() == '\0' || text.back() == ' ')) text.remove_suffix(1);
            }
            if (text.size() > max_label_bytes) {
                if (variable) H5Dvlen_reclaim(memory.get(), in_memory.get(), H5P_DEFAULT, buffer.data());
                refuse(p.field, fmt::format("row {}: a label of {} bytes; mhbench reads labels of at most {} bytes", start + k + 1,
                                            text.size(), max_label_bytes));
            }
            out.rows[static_cast<Eigen::Index>(start + k)] = out.index_of(text);
        }
        if (variable) H5Dvlen_reclaim(memory.get(), in_memory.get(), H5P_DEFAULT, buffer.data());
    }
    return out;
}

TextColumn Hdf5File::read_matlab_chars(Planned& p) const {
    const std::size_t width = p.dims[0], rows = p.dims[1];
    if (H5Tget_size(p.type.get()) == 1) {
        std::vector<std::uint8_t> bytes(width * rows);
        checked(H5Dread(p.dataset.get(), H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()), p.field, "cannot read the characters");
        return char_matrix_labels(bytes.data(), rows, width);
    }
    std::vector<std::uint16_t> units(width * rows);
    checked(H5Dread(p.dataset.get(), H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, units.data()), p.field, "cannot read the characters");
    return char_matrix_labels(units.data(), rows, width);
}

// The text of one cell of a cell array: a char row vector (or an empty array, which is "").
std::string Hdf5File::matlab_text(hid_t object, const std::string& field, std::uint64_t row) const {
    auto refuse_row = [&](const std::string& what) { refuse(field, fmt::format("row {}: {}", row, what)); };
    if (H5Iget_type(object) != H5I_DATASET) refuse_row("the cell holds a struct or a group, not text");
    if (matlab_attribute_set(object, "MATLAB_empty")) return "";
    const std::string matlab = matlab_class(object);
    if (matlab != "char") refuse_row(fmt::format("the cell holds a {}, not text", matlab.empty() ? "value of no MATLAB class" : printable_field(matlab)));
    const Handle space(checked(H5Dget_space(object), field, fmt::format("row {}: cannot read the cell's shape", row)), H5Sclose);
    const Handle type(checked(H5Dget_type(object), field, fmt::format("row {}: cannot read the cell's type", row)), H5Tclose);
    hsize_t dims[2] = {0, 0};
    if (H5Sget_simple_extent_ndims(space.get()) != 2 || H5Tget_class(type.get()) != H5T_INTEGER || H5Tget_size(type.get()) > 2)
        refuse_row("the cell holds a char array in an unsupported encoding or shape");
    H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    if (dims[1] != 1) refuse_row(fmt::format("the cell holds a {}x{} char matrix, not one line of text", dims[1], dims[0]));
    if (dims[0] > max_label_bytes)
        refuse_row(fmt::format("a label of {} characters; mhbench reads labels of at most {} characters", dims[0], max_label_bytes));
    {
        const Handle creation(checked(H5Dget_create_plist(object), field, fmt::format("row {}: cannot read how the cell is stored", row)), H5Pclose);
        if (H5Pget_layout(creation.get()) == H5D_COMPACT) check_compact_size(object, space.get(), type.get(), fmt::format("{}: row {}", field, row));
    }
    TextColumn line;
    if (H5Tget_size(type.get()) == 1) {
        std::vector<std::uint8_t> bytes(dims[0]);
        checked(H5Dread(object, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()), field, fmt::format("row {}: cannot read the cell", row));
        line = char_matrix_labels(bytes.data(), 1, dims[0]);
    } else {
        std::vector<std::uint16_t> units(dims[0]);
        checked(H5Dread(object, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, units.data()), field, fmt::format("row {}: cannot read the cell", row));
        line = char_matrix_labels(units.data(), 1, dims[0]);
    }
    return line.texts[0];
}

TextColumn Hdf5File::read_matlab_cells(Planned& p) const {
    std::vector<hobj_ref_t> references(p.rows);
    checked(H5Dread(p.dataset.get(), H5T_STD_REF_OBJ, H5S_ALL, H5S_ALL, H5P_DEFAULT, references.data()), p.field, "cannot read the cell array");
    TextColumn out;
    out.rows.resize(static_cast<Eigen::Index>(p.rows));
    for (std::size_t k = 0; k < references.size(); ++k) {
        // A reference leads to an object of this file only; HDF5 object references cannot leave it.
        const Handle cell(checked(H5Rdereference2(p.dataset.get(), H5P_DEFAULT, H5R_OBJECT, &references[k]), p.field,
                                  fmt::format("row {}: the cell's reference leads nowhere", k + 1)),
                          H5Oclose);
        out.rows[static_cast<Eigen::Index>(k)] = out.index_of(matlab_text(cell.get(), p.field, k + 1));
    }
    return out;
}

FileColumn Hdf5File::read_planned(Planned& p) const {
    FileColumn column;
    column.name = p.name;
    column.column = p.column;
    switch (p.kind) {
        case Kind::numbers:
            // HDF5 converts every integer and float type to double on reading, exactly up to 2^53.
            column.numbers.resize(static_cast<Eigen::Index>(p.rows));
            checked(H5Dread(p.dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, column.numbers.data()), p.field,
                    "cannot read the numbers");
            break;
        case Kind::strings: column.labels = read_strings(p); break;
        case Kind::matlab_chars: column.labels = read_matlab_chars(p); break;
        case Kind::matlab_cells: column.labels = read_matlab_cells(p); break;
    }
    return column;
}

FileColumns Hdf5File::read(const ColumnChoice& choose) {
    const Handle file = open_file();
    const Handle root(checked(H5Gopen2(file.get(), "/", H5P_DEFAULT), "", "cannot open the root group"), H5Gclose);
    FileColumns out;
    const bool matlab = layout_ == Hdf5Layout::matlab;
    const char* group_kind = matlab ? "struct" : "group";
    // MATLAB keeps what cell arrays refer to, and its own objects' data, under names starting with '#'.
    auto hidden = [&](const Link& link) { return matlab && link.name.starts_with('#'); };
    std::vector<Link> datasets, groups;
    auto sort = [&](std::vector<Link> links, const std::string& where) {
        for (auto& link : links) {
            if (hidden(link)) continue;
            if (link.object == H5O_TYPE_DATASET || link.type == H5L_TYPE_EXTERNAL) datasets.push_back(std::move(link));
            else if (link.object == H5O_TYPE_GROUP) groups.push_back(std::move(link));
            else out.notes.push_back(fmt::format("{}: '{}{}' is neither a dataset nor a group and was ignored", file_, where, printable_field(link.name)));
        }
    };
    sort(links_of(root.get(), ""), "");
    Handle group;
    std::string prefix;
    if (datasets.empty()) {
        if (groups.size() != 1) {
            std::string listing;
            for (const auto& g : groups) listing += (listing.empty() ? "" : ", ") + printable_field(g.name);
            refuse("", groups.empty() ? fmt::format("the {} holds no {}", matlab ? "MAT file" : "HDF5 file", matlab ? "variables" : "datasets")
                                      : fmt::format("no {} at the root but {} {}s ({}); mhbench reads the {} at the root or in a single {}",
                                                    matlab ? "variables" : "datasets", groups.size(), group_kind, listing,
                                                    matlab ? "variables" : "datasets", group_kind));
        }
        prefix = groups[0].name + "/";
        group = Handle(checked(H5Gopen2(root.get(), groups[0].name.c_str(), group_access_.get()), printable_field(groups[0].name),
                               "cannot open the group"),
                       H5Gclose);
        const std::string where = printable_field(prefix);
        groups.clear();
        sort(links_of(group.get(), where), where);
        for (const auto& g : groups) out.notes.push_back(fmt::format("{}: '{}{}' is not a dataset and was ignored", file_, where, printable_field(g.name)));
        groups.clear();
    }
    const hid_t where = group.get() >= 0 ? group.get() : root.get();

    std::vector<std::string> names;
    names.reserve(datasets.size());
    for (const auto& d : datasets) names.push_back(d.name);
    const auto bound = choose(names);
    // Every used dataset is checked, and its rows compared, before any data is read.
    std::vector<Planned> planned;
    DeclaredRows rows(file_);
    for (std::size_t k = 0; k < datasets.size(); ++k) {
        if (bound[k].empty()) {
            out.unused.push_back(datasets[k].name);
            if (datasets[k].type == H5L_TYPE_EXTERNAL)
                out.notes.push_back(fmt::format("{}: '{}{}' is an external link into another file and was not followed", file_,
                                                printable_field(prefix), printable_field(datasets[k].name)));
            continue;
        }
        planned.push_back(plan(where, datasets[k], bound[k], rows));
    }
    for (auto& p : planned) out.columns.push_back(read_planned(p));
    for (const auto& g : groups)
        out.notes.push_back(fmt::format("{}: {} '{}' was ignored: the columns are the {} at the root (a {}'s {} are the columns only "
                                        "when the root holds nothing else)",
                                        file_, group_kind, printable_field(g.name), matlab ? "variables" : "datasets", group_kind,
                                        matlab ? "fields" : "datasets"));
    return out;
}

FileColumns read_file(const std::filesystem::path& path, const ColumnChoice& choose, Hdf5Layout layout) {
    // The library prints its error stack on stderr by default; refusals carry its reason instead.
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return Hdf5File(path, layout).read(choose);
}

}  // namespace
}  // namespace mhb::pmsm

// This file is the library libmhbench_hdf5.so (CMakeLists.txt); the program finds its reader here.
extern "C" [[gnu::visibility("default")]] mhb::pmsm::Hdf5Reader mhbench_hdf5_reader() {
    return &mhb::pmsm::read_file;
}

// HDF5 files through the HDF5 C++ API.
#include <algorithm>
#include <mutex>

#include <H5Cpp.h>
#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "problems/pmsm/data/measurement.hpp"
#include "problems/pmsm/data/measurement_file_columns.hpp"

namespace mhb::pmsm {
namespace {

std::string shape(const std::vector<hsize_t>& dims) {
    if (dims.empty()) return "scalar";
    std::string out;
    for (std::size_t d = 0; d < dims.size(); ++d) out += (d ? "x" : "") + std::to_string(dims[d]);
    return out;
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

// The strings of a string dataset of shape `dims` (a vector of n); fixed-length ones lose the NULs
// or blanks they are padded with.
TextColumn read_strings(const H5::DataSet& dataset, const H5::DataSpace& space, const std::vector<hsize_t>& dims, std::size_t n) {
    const H5::StrType stored = dataset.getStrType();
    TextColumn out;
    out.rows.resize(static_cast<Eigen::Index>(n));
    if (stored.isVariableStr()) {
        // A slab at a time: the library allocates every variable-length string on its own, and a
        // million of them at once would cost more than all the numeric columns, and leave the heap
        // too fragmented to give that memory back.
        constexpr hsize_t slab = 1 << 16;
        const std::size_t axis = dims.size() == 2 && dims[0] == 1 ? 1 : 0;
        const H5::StrType memory(H5::PredType::C_S1, H5T_VARIABLE);
        std::vector<char*> text(static_cast<std::size_t>(std::min<hsize_t>(slab, n)), nullptr);
        for (hsize_t start = 0; start < n; start += slab) {
            std::vector<hsize_t> offset(dims.size(), 0), count = dims;
            offset[axis] = start;
            count[axis] = std::min<hsize_t>(slab, n - start);
            H5::DataSpace in_file = dataset.getSpace();
            in_file.selectHyperslab(H5S_SELECT_SET, count.data(), offset.data());
            const H5::DataSpace in_memory(1, &count[axis]);
            dataset.read(text.data(), memory, in_memory, in_file);
            for (hsize_t k = 0; k < count[axis]; ++k)
                out.rows[static_cast<Eigen::Index>(start + k)] = out.index_of(text[k] ? text[k] : "");
            H5Dvlen_reclaim(memory.getId(), in_memory.getId(), H5P_DEFAULT, text.data());
        }
        return out;
    }
    const std::size_t width = stored.getSize();
    const H5::StrType memory(H5::PredType::C_S1, width);
    std::vector<char> bytes(n * width);
    dataset.read(bytes.data(), memory, space, space);
    for (std::size_t k = 0; k < n; ++k) {
        std::string_view s(bytes.data() + k * width, width);
        while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.remove_suffix(1);
        out.rows[static_cast<Eigen::Index>(k)] = out.index_of(s);
    }
    return out;
}

FileColumn column_from_dataset(const H5::Group& group, const std::string& name) {
    FileColumn column;
    column.name = name;
    const H5::DataSet dataset = group.openDataSet(name);
    const H5::DataSpace space = dataset.getSpace();
    std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(space.getSimpleExtentNdims(), 0)));
    if (!dims.empty()) space.getSimpleExtentDims(dims.data());
    const bool vector = dims.size() == 1 || (dims.size() == 2 && (dims[0] == 1 || dims[1] == 1));
    if (!vector) {
        column.unusable = fmt::format("a {} dataset, not a vector", shape(dims));
        return column;
    }
    const auto n = static_cast<std::size_t>(dims.size() == 1 ? dims[0] : dims[0] * dims[1]);
    if (n > static_cast<std::size_t>(max_measurement_rows)) {
        column.unusable = fmt::format("{} rows; the limit is {} rows", n, max_measurement_rows);
        return column;
    }
    const H5T_class_t type = dataset.getTypeClass();
    if (type == H5T_INTEGER || type == H5T_FLOAT) {
        // HDF5 converts every integer and float type to double on reading, exactly up to 2^53.
        column.numbers.resize(static_cast<Eigen::Index>(n));
        if (n > 0) dataset.read(column.numbers.data(), H5::PredType::NATIVE_DOUBLE, space, space);
    } else if (type == H5T_STRING) {
        column.labels = read_strings(dataset, space, dims, n);
    } else {
        column.unusable = fmt::format("a dataset of {} type; mhbench reads numbers and strings", class_name(type));
    }
    return column;
}

}  // namespace

FileColumns read_hdf5_columns(const std::filesystem::path& path) {
    const std::string file = path.string();
    // HDF5 prints its error stack to stderr by default; the refusal carries the reason instead.
    static std::once_flag quiet;
    std::call_once(quiet, [] { H5::Exception::dontPrint(); });
    std::string current;
    try {
        const H5::H5File h5(file, H5F_ACC_RDONLY);
        const H5::Group root = h5.openGroup("/");
        std::vector<std::string> datasets, groups;
        for (hsize_t k = 0; k < root.getNumObjs(); ++k) {
            const std::string name = root.getObjnameByIdx(k);
            const H5O_type_t type = root.childObjType(name);
            if (type == H5O_TYPE_DATASET) datasets.push_back(name);
            else if (type == H5O_TYPE_GROUP) groups.push_back(name);
        }
        FileColumns out;
        if (datasets.empty()) {
            if (groups.size() != 1) {
                std::string listing;
                for (const auto& g : groups) listing += (listing.empty() ? "" : ", ") + g;
                throw InputError(file, 0, "",
                                 groups.empty() ? std::string("the HDF5 file holds no datasets")
                                                : fmt::format("no datasets at the root but {} groups ({}); mhbench reads the "
                                                              "datasets at the root or in a single group",
                                                              groups.size(), listing));
            }
            current = groups[0];
            const H5::Group group = root.openGroup(groups[0]);
            for (hsize_t k = 0; k < group.getNumObjs(); ++k) {
                const std::string name = group.getObjnameByIdx(k);
                if (group.childObjType(name) != H5O_TYPE_DATASET) {
                    out.notes.push_back(fmt::format("{}: '{}/{}' is not a dataset and was ignored", file, groups[0], name));
                    continue;
                }
                current = groups[0] + "/" + name;
                out.columns.push_back(column_from_dataset(group, name));
            }
            return out;
        }
        for (const auto& name : datasets) {
            current = name;
            out.columns.push_back(column_from_dataset(root, name));
        }
        for (const auto& g : groups)
            out.notes.push_back(fmt::format("{}: group '{}' was ignored: the columns are the datasets at the root (a group's "
                                            "datasets are the columns only when the root holds no datasets and that one group)",
                                            file, g));
        return out;
    } catch (const H5::Exception& e) {
        throw InputError(file, 0, current,
                         fmt::format("cannot read the HDF5 file (truncated or damaged?): {} ({})", e.getDetailMsg(), e.getFuncName()));
    }
}

}  // namespace mhb::pmsm

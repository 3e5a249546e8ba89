#pragma once
// MAT (v5, v7, v7.3) and HDF5 measurement files written with matio's and HDF5's own write APIs, so
// that the reader tests need no MATLAB: the valid files they read, and the ones they damage.
#include <map>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <H5Cpp.h>
#include <matio.h>

#include "problems/pmsm/data/measurement.hpp"

namespace mhb::testing {

using mhb::pmsm::Measurement;
namespace fs = std::filesystem;

// A column as a test file holds it: numbers or labels, under the file's own name.
struct WrittenColumn {
    std::string name;
    std::vector<double> numbers;
    std::vector<std::string> labels;
};

inline std::vector<double> values(const Eigen::VectorXd& v) { return {v.data(), v.data() + v.size()}; }

inline std::vector<std::string> labels_of(const Measurement& m) {
    std::vector<std::string> out;
    for (Eigen::Index r = 0; r < m.size(); ++r) out.push_back(m.segment_labels[static_cast<std::size_t>(m.segment[r])]);
    return out;
}

// Every column of `m` under mhbench's names, `renamed` replacing some of them.
inline std::vector<WrittenColumn> columns_of(const Measurement& m, const std::map<std::string, std::string>& renamed = {}) {
    auto name = [&](const std::string& n) { return renamed.count(n) ? renamed.at(n) : n; };
    std::vector<WrittenColumn> out;
    out.push_back({name("t"), values(*m.t), {}});
    out.push_back({name("segment"), {}, labels_of(m)});
    out.push_back({name("theta_e"), values(*m.theta_e), {}});
    out.push_back({name("i_d"), values(m.i_d), {}});
    out.push_back({name("i_q"), values(m.i_q), {}});
    out.push_back({name("u_d"), values(m.u_d), {}});
    out.push_back({name("u_q"), values(m.u_q), {}});
    out.push_back({name("omega_e"), values(m.omega_e), {}});
    out.push_back({name("temp_winding"), values(*m.temp_winding), {}});
    out.push_back({name("temp_magnet"), values(*m.temp_magnet), {}});
    return out;
}

inline matvar_t* mat_variable(const WrittenColumn& c, bool named) {
    const char* name = named ? c.name.c_str() : nullptr;
    if (c.labels.empty()) {
        std::size_t dims[2] = {c.numbers.size(), 1};
        return Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, const_cast<double*>(c.numbers.data()), 0);
    }
    std::size_t dims[2] = {c.labels.size(), 1};
    matvar_t* cell = Mat_VarCreate(name, MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0);
    for (std::size_t k = 0; k < c.labels.size(); ++k) {
        std::size_t text_dims[2] = {1, c.labels[k].size()};
        Mat_VarSetCell(cell, static_cast<int>(k),
                       Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, text_dims, const_cast<char*>(c.labels[k].data()), 0));
    }
    return cell;
}

// A MAT file with one variable per column, or (with `struct_name`) one struct with a field per column.
inline void write_mat(const fs::path& path, mat_ft version, const std::vector<WrittenColumn>& columns,
               const std::string& struct_name = "", matio_compression compression = MAT_COMPRESSION_NONE) {
    mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, version);
    REQUIRE(mat);
    if (struct_name.empty()) {
        for (const auto& c : columns) {
            matvar_t* v = mat_variable(c, true);
            REQUIRE(Mat_VarWrite(mat, v, compression) == 0);
            Mat_VarFree(v);
        }
    } else {
        std::vector<const char*> fields;
        for (const auto& c : columns) fields.push_back(c.name.c_str());
        std::size_t dims[2] = {1, 1};
        matvar_t* s = Mat_VarCreateStruct(struct_name.c_str(), 2, dims, fields.data(), static_cast<unsigned>(fields.size()));
        for (const auto& c : columns) Mat_VarSetStructFieldByName(s, c.name.c_str(), 0, mat_variable(c, true));
        REQUIRE(Mat_VarWrite(mat, s, compression) == 0);
        Mat_VarFree(s);
    }
    Mat_Close(mat);
}

inline void write_hdf5_column(H5::Group& group, const WrittenColumn& c) {
    if (c.labels.empty()) {
        const hsize_t dims[1] = {c.numbers.size()};
        auto ds = group.createDataSet(c.name, H5::PredType::IEEE_F64LE, H5::DataSpace(1, dims));
        ds.write(c.numbers.data(), H5::PredType::NATIVE_DOUBLE);
        return;
    }
    const hsize_t dims[1] = {c.labels.size()};
    const H5::StrType text(H5::PredType::C_S1, H5T_VARIABLE);
    std::vector<const char*> pointers;
    for (const auto& l : c.labels) pointers.push_back(l.c_str());
    auto ds = group.createDataSet(c.name, text, H5::DataSpace(1, dims));
    ds.write(pointers.data(), text);
}

// An HDF5 file with one dataset per column at the root, or in the group `group_name`.
inline void write_hdf5(const fs::path& path, const std::vector<WrittenColumn>& columns, const std::string& group_name = "") {
    H5::H5File file(path.string(), H5F_ACC_TRUNC);
    H5::Group group = group_name.empty() ? file.openGroup("/") : file.createGroup(group_name);
    for (const auto& c : columns) write_hdf5_column(group, c);
}

}  // namespace mhb::testing

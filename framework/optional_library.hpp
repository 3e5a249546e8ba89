#pragma once
// Parts of mhbench that need large libraries of their own are shared objects of their own, installed
// beside the core library and loaded by the first command that uses them: libmhbench_hdf5.so (HDF5
// and MAT v7.3 files; libhdf5 brings libcurl, TLS, Kerberos and LDAP, about 30 libraries) and
// libmhbench_mpi.so (`mpirun ... mhbench run`; Open MPI). Every other command starts without
// mapping and relocating them (docs/performance.md, "The program's start").
#include <string>

namespace mhb {

// The file the optional library `name` ("hdf5" for libmhbench_hdf5.so) is loaded from: in the
// directory of the core library (libmhbench.so) that this process runs.
std::string optional_library_path(const std::string& name);

// The address of `symbol` in the optional library `name`, loaded on the first call (thread-safe;
// never unloaded). Throws std::runtime_error naming the file and the dynamic loader's reason when
// the library or the symbol cannot be found: an incomplete installation, not bad input.
void* optional_library_symbol(const std::string& name, const char* symbol);

// The entry point `symbol` of the optional library `name`: a function of no arguments with C linkage
// that returns what the library offers (a function pointer, a table of them).
template <class Entry>
Entry* optional_library_entry(const std::string& name, const char* symbol) {
    return reinterpret_cast<Entry*>(optional_library_symbol(name, symbol));
}

}  // namespace mhb

#pragma once
// MHB_ROW_KERNEL before a function whose loop over a block's rows is element-wise (each row's
// outputs from that row's inputs, no sum across rows; or sums kept in an order the source fixes,
// fit/packet_order_sums.hpp) compiles it twice, for AVX2 and for baseline x86-64, and the loader
// picks the processor's once (GCC's target_clones). Both clones give the same bits: the same
// operations on each row, and neither fuses a multiply with an add (AVX2 brings no FMA, and the
// build's ISO C++ contracts nothing). Only the width differs, four rows at a time instead of two,
// which pays where a loop divides or takes square roots. Other compilers and processors get the one
// baseline function.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define MHB_ROW_KERNEL [[gnu::target_clones("avx2", "default")]]
#else
#define MHB_ROW_KERNEL
#endif

#include <Eigen/Core>

namespace mhb::pmsm {

// The pairs (x, y) of n rows turned by the angle whose cosine and sine are c and s, in place:
// (x c - y s, y c + x s), as the complex product gives them but without its branch for NaN results,
// which stops a loop from vectorising. (Not in effect.hpp: a helper of the built-in effects, not
// part of the plugin interface.)
void turn_rows(double c, double s, Eigen::Index n, double* x, double* y);

}  // namespace mhb::pmsm

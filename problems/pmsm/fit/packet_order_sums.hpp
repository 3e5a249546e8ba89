#pragma once
// Dot products of columns summed in the order Eigen 3.4 sums them with packets of two doubles (the
// SSE2 of a baseline x86-64 build), several at once. Eigen's reduction keeps two packets, so four
// running sums (row 4m + l into sum l, each started at its first product), adds them pairwise as
// (s0 + s2) + (s1 + s3) with the last pair of rows folded into the two halves first, then the odd last
// row; each sum waits on its own additions, and one dot product at a time leaves the adder idle most
// of the time. Several in one loop keep it busy, with every sum's order unchanged, so the fits'
// normal equations keep their bits (and no longer depend on the packet size a build gives Eigen).
#include <cstddef>

#include <Eigen/Core>

namespace mhb::pmsm {

struct ColumnPair {
    const double* a;
    const double* b;
};

// out[k] = sum over r < n of pairs[k].a[r] * pairs[k].b[r], in the order above; 0 when n is 0.
void packet_order_dots(const ColumnPair* pairs, std::size_t count, Eigen::Index n, double* out);

}  // namespace mhb::pmsm

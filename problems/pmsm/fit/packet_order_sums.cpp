#include "problems/pmsm/fit/packet_order_sums.hpp"

#include <cstring>

#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {
namespace {

// Four doubles as one value: an AVX2 register, or two SSE2 registers in the baseline clone. Written
// so because a compiler left to vectorise the loop itself sums each product row by row, in order,
// which is the slow way.
using Quad = double __attribute__((vector_size(4 * sizeof(double))));

#define MHB_LOAD_QUAD(v, p) std::memcpy(&(v), (p), sizeof(Quad))

// K sums in flight at once.
template <int K>
[[gnu::always_inline]] inline void dots(const ColumnPair* pairs, Eigen::Index n, double* out) {
    if (n < 4) {
        for (int k = 0; k < K; ++k) {
            const double *a = pairs[k].a, *b = pairs[k].b;
            double r = n == 0 ? 0.0 : a[0] * b[0];
            if (n >= 2) r += a[1] * b[1];
            if (n == 3) r += a[2] * b[2];
            out[k] = r;
        }
        return;
    }
    const Eigen::Index quads = n / 4 * 4, pairs_end = n / 2 * 2;
    const double* a[K];
    const double* b[K];
    Quad s[K];
    for (int k = 0; k < K; ++k) {
        a[k] = pairs[k].a;
        b[k] = pairs[k].b;
        Quad x, y;
        MHB_LOAD_QUAD(x, a[k]);
        MHB_LOAD_QUAD(y, b[k]);
        s[k] = x * y;
    }
    for (Eigen::Index i = 4; i < quads; i += 4)
        for (int k = 0; k < K; ++k) {
            Quad x, y;
            MHB_LOAD_QUAD(x, a[k] + i);
            MHB_LOAD_QUAD(y, b[k] + i);
            s[k] += x * y;
        }
    for (int k = 0; k < K; ++k) {
        double low = s[k][0] + s[k][2], high = s[k][1] + s[k][3];
        if (pairs_end > quads) {
            low += a[k][quads] * b[k][quads];
            high += a[k][quads + 1] * b[k][quads + 1];
        }
        double r = low + high;
        if (n > pairs_end) r += a[k][n - 1] * b[k][n - 1];
        out[k] = r;
    }
}

}  // namespace

// With AVX2 the four sums of a product fill one register.
MHB_ROW_KERNEL void packet_order_dots(const ColumnPair* pairs, std::size_t count, Eigen::Index n, double* out) {
    std::size_t k = 0;
    for (; k + 4 <= count; k += 4) dots<4>(pairs + k, n, out + k);
    switch (count - k) {
    case 3: dots<3>(pairs + k, n, out + k); break;
    case 2: dots<2>(pairs + k, n, out + k); break;
    case 1: dots<1>(pairs + k, n, out + k); break;
    default: break;
    }
}

}  // namespace mhb::pmsm

#undef MHB_LOAD_QUAD

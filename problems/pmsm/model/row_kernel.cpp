#include "problems/pmsm/model/row_kernel.hpp"

namespace mhb::pmsm {

MHB_ROW_KERNEL void turn_rows(double c, double s, Eigen::Index n, double* __restrict x, double* __restrict y) {
    for (Eigen::Index k = 0; k < n; ++k) {
        const double a = x[k], b = y[k];
        x[k] = c * a - s * b;
        y[k] = c * b + s * a;
    }
}

}  // namespace mhb::pmsm

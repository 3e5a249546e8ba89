// Several dot products at once, each summed in the order Eigen 3.4 sums one with packets of two
// doubles: against that order written out row by row, and against Eigen's own dot product where
// this build gives Eigen packets of two doubles (there the fits' normal equations keep their bits).
#include <catch2/catch.hpp>

#include <bit>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "framework/random.hpp"
#include "problems/pmsm/fit/packet_order_sums.hpp"

using namespace mhb;
using namespace mhb::pmsm;

namespace {

// The order as the header states it, one product at a time.
double stated_order(const double* a, const double* b, Eigen::Index n) {
    if (n == 0) return 0.0;
    if (n < 4) {
        double r = a[0] * b[0];
        for (Eigen::Index i = 1; i < n; ++i) r += a[i] * b[i];
        return r;
    }
    double s[4];
    for (int l = 0; l < 4; ++l) s[l] = a[l] * b[l];
    const Eigen::Index quads = n / 4 * 4;
    for (Eigen::Index i = 4; i < quads; ++i) s[i % 4] += a[i] * b[i];
    double low = s[0] + s[2], high = s[1] + s[3];
    if (n - quads >= 2) {
        low += a[quads] * b[quads];
        high += a[quads + 1] * b[quads + 1];
    }
    double r = low + high;
    if (n % 2 == 1) r += a[n - 1] * b[n - 1];
    return r;
}

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

}  // namespace

TEST_CASE("packet_order_dots sums each product in Eigen's two-double packet order", "[pmsm][packet_order_sums]") {
    Rng rng(20261127);
    // Values of mixed sign and size, so that a different order of the additions changes the bits.
    Eigen::MatrixXd columns(1100, 7);
    for (Eigen::Index j = 0; j < columns.cols(); ++j)
        for (Eigen::Index r = 0; r < columns.rows(); ++r) columns(r, j) = (rng.uniform() - 0.5) * std::pow(10.0, 6.0 * rng.uniform() - 3.0);
    const bool eigen_packets_of_two = Eigen::internal::packet_traits<double>::Vectorizable && Eigen::internal::packet_traits<double>::size == 2;
    int differ_from_naive = 0, compared = 0;
    for (Eigen::Index n : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 31, 510, 511, 512, 513, 514, 1025}) {
        for (Eigen::Index offset : {0, 1, 3}) {  // columns starting off the packets' alignment, as a segment's rows do
            std::vector<ColumnPair> pairs;
            for (Eigen::Index i = 0; i < columns.cols(); ++i)
                for (Eigen::Index j = i; j < columns.cols(); ++j) pairs.push_back({columns.col(i).data() + offset, columns.col(j).data() + offset});
            for (std::size_t count : {std::size_t{1}, std::size_t{3}, std::size_t{4}, std::size_t{9}, pairs.size()}) {
                std::vector<double> out(count, -1.0);
                packet_order_dots(pairs.data(), count, n, out.data());
                for (std::size_t k = 0; k < count; ++k) {
                    const Eigen::Map<const Eigen::VectorXd> a(pairs[k].a, n), b(pairs[k].b, n);
                    INFO("n " << n << ", offset " << offset << ", pair " << k << " of " << count);
                    REQUIRE(bits(out[k]) == bits(stated_order(pairs[k].a, pairs[k].b, n)));
                    if (eigen_packets_of_two) REQUIRE(bits(out[k]) == bits(a.dot(b)));
                    double naive = 0.0;
                    for (Eigen::Index r = 0; r < n; ++r) naive += pairs[k].a[r] * pairs[k].b[r];
                    ++compared;
                    if (bits(naive) != bits(out[k])) ++differ_from_naive;
                }
            }
        }
    }
    // The data are such that the order shows: a sum from the first row to the last differs in many.
    CHECK(differ_from_naive > compared / 4);
}

#include "framework/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>

namespace mhb::stats {

Summary summarize(std::span<const double> values) {
    Summary s;
    s.n = values.size();
    if (s.n == 0) return s;
    std::vector<double> v(values.begin(), values.end());
    std::sort(v.begin(), v.end());
    s.min = v.front();
    s.max = v.back();
    s.median = quantile(v, 0.5);
    s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(s.n);
    if (s.n > 1) {
        double ss = 0;
        for (double x : v) ss += (x - s.mean) * (x - s.mean);
        s.sd = std::sqrt(ss / static_cast<double>(s.n - 1));
    }
    return s;
}

double quantile(std::vector<double> values, double p) {
    if (values.empty()) return std::nan("");
    std::sort(values.begin(), values.end());
    const double h = p * static_cast<double>(values.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(h));
    const auto hi = std::min(lo + 1, values.size() - 1);
    return values[lo] + (h - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

std::vector<double> holm_adjusted(std::span<const double> p) {
    std::vector<std::size_t> order(p.size());
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
    std::vector<double> adjusted(p.size());
    double running = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
        running = std::max(running, std::min(1.0, static_cast<double>(p.size() - i) * p[order[i]]));
        adjusted[order[i]] = running;
    }
    return adjusted;
}

std::vector<double> average_ranks(std::span<const double> values) {
    const std::size_t n = values.size();
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
    std::vector<double> ranks(n);
    for (std::size_t i = 0; i < n;) {
        std::size_t j = i;
        while (j + 1 < n && values[order[j + 1]] == values[order[i]]) ++j;
        const double rank = 0.5 * static_cast<double>(i + j) + 1.0;
        for (std::size_t k = i; k <= j; ++k) ranks[order[k]] = rank;
        i = j + 1;
    }
    return ranks;
}

namespace {
// Exact two-sided p-value of U for samples of sizes m and n without ties: the number of
// arrangements with each U value, by the recurrence c(m, n, u) = c(m-1, n, u-n) + c(m, n-1, u).
double exact_rank_sum_p(std::size_t m, std::size_t n, double u) {
    const std::size_t max_u = m * n;
    // counts[j][u] for the current i, rolling over i.
    std::vector<std::vector<double>> prev(n + 1, std::vector<double>(max_u + 1, 0.0)), cur = prev;
    for (std::size_t j = 0; j <= n; ++j) prev[j][0] = 1.0;  // i = 0: only U = 0
    for (std::size_t i = 1; i <= m; ++i) {
        for (auto& row : cur) std::fill(row.begin(), row.end(), 0.0);
        cur[0][0] = 1.0;
        for (std::size_t j = 1; j <= n; ++j)
            for (std::size_t k = 0; k <= i * j; ++k) {
                // the largest of the i + j values belongs to sample 1 (adds j to U) or to sample 2
                double c = cur[j - 1][k];
                if (k >= j) c += prev[j][k - j];
                cur[j][k] = c;
            }
        std::swap(prev, cur);
    }
    const auto& counts = prev[n];
    const double total = std::accumulate(counts.begin(), counts.end(), 0.0);
    const double mean = 0.5 * static_cast<double>(max_u);
    const double d = std::abs(u - mean);
    double tail = 0;
    for (std::size_t k = 0; k <= max_u; ++k)
        if (std::abs(static_cast<double>(k) - mean) >= d - 1e-9) tail += counts[k];
    return std::min(1.0, tail / total);
}
}  // namespace

RankSumResult wilcoxon_rank_sum(std::span<const double> a, std::span<const double> b) {
    RankSumResult r;
    const std::size_t m = a.size(), n = b.size();
    if (m == 0 || n == 0) return r;
    std::vector<double> all(a.begin(), a.end());
    all.insert(all.end(), b.begin(), b.end());
    const auto ranks = average_ranks(all);
    const double rank_sum_a = std::accumulate(ranks.begin(), ranks.begin() + static_cast<long>(m), 0.0);
    r.u = rank_sum_a - static_cast<double>(m * (m + 1)) / 2.0;

    // Tie correction of the variance: sum over tie groups of (t^3 - t).
    std::vector<double> sorted = all;
    std::sort(sorted.begin(), sorted.end());
    double tie_term = 0;
    bool ties = false;
    for (std::size_t i = 0; i < sorted.size();) {
        std::size_t j = i;
        while (j + 1 < sorted.size() && sorted[j + 1] == sorted[i]) ++j;
        const double t = static_cast<double>(j - i + 1);
        if (t > 1) ties = true;
        tie_term += t * t * t - t;
        i = j + 1;
    }
    const double N = static_cast<double>(m + n);
    const double mean_u = static_cast<double>(m * n) / 2.0;
    const double var_u = static_cast<double>(m * n) / 12.0 * ((N + 1) - tie_term / (N * (N - 1)));
    if (var_u <= 0) {  // every value equal: no evidence of a difference
        r.p = 1.0;
        return r;
    }
    const double diff = r.u - mean_u;
    const double corrected = std::max(0.0, std::abs(diff) - 0.5);
    r.z = (diff < 0 ? -1.0 : 1.0) * corrected / std::sqrt(var_u);
    if (!ties && m * n <= 2500) {
        r.p = exact_rank_sum_p(m, n, r.u);
        r.exact = true;
    } else {
        boost::math::normal_distribution<> normal;
        r.p = std::min(1.0, 2.0 * boost::math::cdf(boost::math::complement(normal, std::abs(r.z))));
    }
    return r;
}

double vargha_delaney_a12(std::span<const double> a, std::span<const double> b) {
    if (a.empty() || b.empty()) return std::nan("");
    double wins = 0;
    for (double x : a)
        for (double y : b) wins += x < y ? 1.0 : (x == y ? 0.5 : 0.0);
    return wins / static_cast<double>(a.size() * b.size());
}

const char* a12_magnitude(double a12) {
    // Vargha & Delaney (2000) thresholds on |A - 0.5|: 0.06, 0.14, 0.21.
    const double d = std::abs(a12 - 0.5);
    if (d < 0.06) return "negligible";
    if (d < 0.14) return "small";
    if (d < 0.21) return "medium";
    return "large";
}

FriedmanResult friedman(const std::vector<std::vector<double>>& scores) {
    FriedmanResult r;
    if (scores.empty()) return r;
    const std::size_t k = scores.front().size();
    const double blocks = static_cast<double>(scores.size());
    r.mean_ranks.assign(k, 0.0);
    double tie_term = 0;
    for (const auto& row : scores) {
        if (row.size() != k) throw std::invalid_argument("friedman: every block needs one score per algorithm");
        const auto ranks = average_ranks(row);
        for (std::size_t j = 0; j < k; ++j) r.mean_ranks[j] += ranks[j];
        std::vector<double> sorted = row;
        std::sort(sorted.begin(), sorted.end());
        for (std::size_t i = 0; i < k;) {
            std::size_t j = i;
            while (j + 1 < k && sorted[j + 1] == sorted[i]) ++j;
            const double t = static_cast<double>(j - i + 1);
            tie_term += t * t * t - t;
            i = j + 1;
        }
    }
    for (auto& m : r.mean_ranks) m /= blocks;
    if (k < 2) return r;
    const double kk = static_cast<double>(k);
    double ss = 0;
    for (double m : r.mean_ranks) ss += (m - (kk + 1) / 2) * (m - (kk + 1) / 2);
    const double denominator = 1.0 - tie_term / (blocks * (kk * kk * kk - kk));
    if (denominator <= 0) return r;  // all ties in every block
    r.chi_square = 12.0 * blocks / (kk * (kk + 1)) * ss / denominator;
    boost::math::chi_squared_distribution<> chi2(kk - 1);
    r.p = boost::math::cdf(boost::math::complement(chi2, r.chi_square));
    return r;
}

}  // namespace mhb::stats

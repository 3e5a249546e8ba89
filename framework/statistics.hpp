#pragma once
// Descriptive statistics and the significance tests used in result tables.
#include <span>
#include <vector>

namespace mhb::stats {

struct Summary {
    std::size_t n = 0;
    double mean = 0, sd = 0, median = 0, min = 0, max = 0;  // sd: sample standard deviation (n - 1)
};
Summary summarize(std::span<const double> values);

double quantile(std::vector<double> values, double p);  // linear interpolation (type 7)

// Ranks 1..n with ties given their average rank.
std::vector<double> average_ranks(std::span<const double> values);

struct RankSumResult {
    double u = 0;        // Mann-Whitney U of the first sample: pairs (a, b) with a > b, ties count 1/2
    double z = 0;        // normal approximation (with tie and continuity correction)
    double p = 1;        // two-sided p-value
    bool exact = false;  // true when p comes from the exact null distribution (no ties, small samples)
};
// Wilcoxon rank-sum (Mann-Whitney U) test of two independent samples, two-sided. The p-value is
// exact when there are no ties and n1 * n2 <= 2500, else the normal approximation.
RankSumResult wilcoxon_rank_sum(std::span<const double> a, std::span<const double> b);

// Vargha-Delaney A12 for minimisation: P(a < b) + P(a = b) / 2, the probability that a run of A
// ends lower (better) than a run of B. 0.5 = no difference; > 0.71 or < 0.29 is a "large" effect.
double vargha_delaney_a12(std::span<const double> a, std::span<const double> b);
const char* a12_magnitude(double a12);  // "negligible", "small", "medium", "large"

// Holm's step-down adjustment of m p-values for multiple comparisons (Holm 1979): the i-th smallest
// becomes max over j <= i of min(1, (m - j + 1) p_(j)); returned in the order given. Rejecting where
// the adjusted p < alpha keeps the family-wise error rate at alpha.
std::vector<double> holm_adjusted(std::span<const double> p);

struct FriedmanResult {
    std::vector<double> mean_ranks;  // per algorithm, rank 1 = best (lowest)
    double chi_square = 0;
    double p = 1;                    // chi-square approximation, k - 1 degrees of freedom
};
// `scores[block][algorithm]`: one block per problem (e.g. mean final fitness), lower is better.
FriedmanResult friedman(const std::vector<std::vector<double>>& scores);

}  // namespace mhb::stats

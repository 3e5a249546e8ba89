#pragma once
// One-to-one greedy survivor selection, shared by the population optimisers. A candidate replaces
// its parent only when strictly better: ties keep the parent, as SO.m (`if y < fitness`), mealpy's
// GWO and JADE's success rule do. Candidates the evaluator skipped (budget spent) carry +inf and so
// never replace anything.
#include <vector>

#include "framework/problem.hpp"

namespace mhb {

// Replaces column i of `population` (and fitness[i]) by candidate i when candidate_fitness[i] <
// fitness[i]. Returns how many columns were replaced; `accepted`, when given (sized like fitness),
// records which.
inline Eigen::Index greedy_replace(Eigen::Ref<Matrix> population, Eigen::Ref<Vector> fitness,
                                   const Eigen::Ref<const Matrix>& candidates,
                                   const Eigen::Ref<const Vector>& candidate_fitness,
                                   std::vector<char>* accepted = nullptr) {
    Eigen::Index replaced = 0;
    for (Eigen::Index i = 0; i < fitness.size(); ++i) {
        const bool better = candidate_fitness[i] < fitness[i];
        if (accepted) (*accepted)[static_cast<std::size_t>(i)] = better;
        if (!better) continue;
        population.col(i) = candidates.col(i);
        fitness[i] = candidate_fitness[i];
        ++replaced;
    }
    return replaced;
}

// Index of the smallest fitness (the first one among ties, as MATLAB's min).
inline Eigen::Index index_of_best(const Eigen::Ref<const Vector>& fitness) {
    Eigen::Index best = 0;
    for (Eigen::Index i = 1; i < fitness.size(); ++i)
        if (fitness[i] < fitness[best]) best = i;
    return best;
}

// Index of the largest fitness (the first one among ties, as MATLAB's max).
inline Eigen::Index index_of_worst(const Eigen::Ref<const Vector>& fitness) {
    Eigen::Index worst = 0;
    for (Eigen::Index i = 1; i < fitness.size(); ++i)
        if (fitness[i] > fitness[worst]) worst = i;
    return worst;
}

}  // namespace mhb

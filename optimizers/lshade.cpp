// L-SHADE: R. Tanabe, A. Fukunaga, "Improving the search performance of SHADE using linear
// population size reduction", IEEE CEC 2014, 1658-1665. Generational as the authors' code: the whole
// trial population is built, evaluated in one call, then selected.
#include "optimizers/lshade.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"

namespace mhb::shade {

Eigen::Index planned_population(Eigen::Index initial, Eigen::Index minimum, double used) {
    const double n = std::round((static_cast<double>(minimum - initial)) * used + static_cast<double>(initial));
    return std::max(minimum, static_cast<Eigen::Index>(n));
}

double weighted_lehmer_mean(const std::vector<double>& values, const std::vector<double>& improvements) {
    const double total = std::accumulate(improvements.begin(), improvements.end(), 0.0);
    double squares = 0.0, plain = 0.0;
    for (std::size_t k = 0; k < values.size(); ++k) {
        const double w = improvements[k] / total;
        squares += w * values[k] * values[k];
        plain += w * values[k];
    }
    return squares / plain;
}

Settings settings_from(const ParameterSet& p) {
    Settings s;
    s.initial_population = p.integer("population");
    s.archive_rate = p.real("archive_rate");
    s.memory_size = static_cast<int>(p.integer("memory_size"));
    s.p_best = p.real("p_best");
    s.archive_entry = p.text("archive_entry") == "trial" ? ArchiveEntry::trial : ArchiveEntry::parent;
    s.sticky_terminal_cr = p.boolean("sticky_terminal_cr");
    if (s.initial_population != 0 && s.initial_population < s.minimum_population)
        throw ParameterError("population", "must be 0 (the paper's rule) or at least 4, the final population (got " +
                                               std::to_string(s.initial_population) + ")");
    return s;
}

ParameterSpec archive_entry_parameter() {
    return ParameterSpec::choice("archive_entry", "parent", {"parent", "trial"},
                                 "what a successful trial sends to the archive: the parent it replaced (the papers) "
                                 "or the trial itself (Tanabe's code)");
}

Eigen::Index Lshade::initial_population(int dimension) const {
    return static_cast<Eigen::Index>(std::round(18.0 * dimension));  // r^Ninit = 18
}

std::pair<double, double> Lshade::memory_means(int slot) const {
    return {memory_f_[static_cast<std::size_t>(slot)], memory_cr_[static_cast<std::size_t>(slot)]};
}

double Lshade::adjusted_cr(double cr, double) const { return cr; }
double Lshade::adjusted_f(double f, double) const { return f; }
double Lshade::pbest_factor(double f, double) const { return f; }
double Lshade::p_best_rate(double) const { return settings_.p_best; }
bool Lshade::pbest_may_be_target(double) const { return true; }

std::pair<double, double> Lshade::updated_memory(double, double old_cr, double f_mean, double cr_mean) const {
    // The paper keeps ⊥ once reached (Algorithm 1); Tanabe's code resets it (docs/algorithms.md).
    const bool keep_terminal = settings_.sticky_terminal_cr && old_cr == terminal_cr;
    return {f_mean, keep_terminal ? terminal_cr : cr_mean};
}

void Lshade::initialize(Evaluator& evaluator, Rng& rng) {
    const int d = evaluator.dimension();
    initial_ = settings_.initial_population != 0 ? settings_.initial_population : initial_population(d);
    initial_ = std::max(initial_, settings_.minimum_population);
    population_.resize(d, initial_);
    trials_.resize(d, initial_);
    fitness_.resize(initial_);
    trial_fitness_.resize(initial_);
    archive_capacity_ = static_cast<Eigen::Index>(std::round(static_cast<double>(initial_) * settings_.archive_rate));
    archive_.resize(d, std::max<Eigen::Index>(archive_capacity_, 1));
    archive_count_ = 0;
    memory_f_.assign(static_cast<std::size_t>(settings_.memory_size), settings_.initial_memory_f);
    memory_cr_.assign(static_cast<std::size_t>(settings_.memory_size), settings_.initial_memory_cr);
    memory_position_ = 0;
    fill_uniform(population_, evaluator.bounds(), rng);
    evaluator.evaluate(population_, fitness_);
}

void Lshade::make_trial(Eigen::Index i, Eigen::Index pbest, double f, double cr, double used, const Bounds& bounds, Rng& rng) {
    const Eigen::Index n = population_.cols(), d = population_.rows();
    Eigen::Index r1, r2;
    do r1 = static_cast<Eigen::Index>(rng.below(static_cast<std::uint64_t>(n)));
    while (r1 == i);
    do r2 = static_cast<Eigen::Index>(rng.below(static_cast<std::uint64_t>(n + archive_count_)));
    while (r2 == i || r2 == r1);
    const auto second = r2 < n ? population_.col(r2) : archive_.col(r2 - n);
    const double fw = pbest_factor(f, used);
    const auto j_rand = static_cast<Eigen::Index>(rng.below(static_cast<std::uint64_t>(d)));
    for (Eigen::Index j = 0; j < d; ++j) {
        const double parent = population_(j, i);
        if (!(rng.uniform() < cr || j == j_rand)) {
            trials_(j, i) = parent;
            continue;
        }
        double v = parent + fw * (population_(j, pbest) - parent) + f * (population_(j, r1) - second[j]);
        // Halfway between the parent and the violated bound (the authors' code; the paper is silent).
        if (v < bounds.lower[j]) v = (bounds.lower[j] + parent) / 2.0;
        else if (v > bounds.upper[j]) v = (bounds.upper[j] + parent) / 2.0;
        trials_(j, i) = v;
    }
}

void Lshade::iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) {
    const Eigen::Index n = population_.cols();
    const std::int64_t max_evaluations = progress.budget.max_evaluations;
    const double used = max_evaluations > 0
                            ? std::min(1.0, static_cast<double>(progress.evaluations) / static_cast<double>(max_evaluations))
                            : progress.fraction();
    order_.resize(static_cast<std::size_t>(n));
    std::iota(order_.begin(), order_.end(), Eigen::Index{0});
    std::stable_sort(order_.begin(), order_.end(), [&](Eigen::Index a, Eigen::Index b) { return fitness_[a] < fitness_[b]; });
    const auto p_count = std::max<Eigen::Index>(2, static_cast<Eigen::Index>(std::round(static_cast<double>(n) * p_best_rate(used))));
    f_.resize(static_cast<std::size_t>(n));
    cr_.resize(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) {
        const int slot = static_cast<int>(rng.below(static_cast<std::uint64_t>(settings_.memory_size)));
        const auto [mu_f, mu_cr] = memory_means(slot);
        double cr = mu_cr < 0 ? 0.0 : std::clamp(rng.normal(mu_cr, 0.1), 0.0, 1.0);
        cr = adjusted_cr(cr, used);
        double f;
        do f = rng.cauchy(mu_f, 0.1);
        while (f <= 0.0);
        f = adjusted_f(std::min(f, 1.0), used);
        Eigen::Index pbest;
        do pbest = order_[static_cast<std::size_t>(rng.below(static_cast<std::uint64_t>(std::min(p_count, n))))];
        while (pbest == i && !pbest_may_be_target(used));
        f_[static_cast<std::size_t>(i)] = f;
        cr_[static_cast<std::size_t>(i)] = cr;
        make_trial(i, pbest, f, cr, used, evaluator.bounds(), rng);
    }
    evaluator.evaluate(trials_.leftCols(n), trial_fitness_.head(n));

    for (Eigen::Index i = 0; i < n; ++i) {
        if (trial_fitness_[i] > fitness_[i]) continue;
        if (trial_fitness_[i] < fitness_[i]) {
            success_f_.push_back(f_[static_cast<std::size_t>(i)]);
            success_cr_.push_back(cr_[static_cast<std::size_t>(i)]);
            improvement_.push_back(fitness_[i] - trial_fitness_[i]);
            if (archive_capacity_ > 0) {
                // A full archive gives a random member's place to the new one.
                const Eigen::Index slot = archive_count_ < archive_capacity_
                                              ? archive_count_++
                                              : static_cast<Eigen::Index>(rng.below(static_cast<std::uint64_t>(archive_capacity_)));
                archive_.col(slot) = settings_.archive_entry == ArchiveEntry::parent ? population_.col(i) : trials_.col(i);
            }
        }
        population_.col(i) = trials_.col(i);
        fitness_[i] = trial_fitness_[i];
    }
    update_memory();

    const double used_after = max_evaluations > 0 ? std::min(1.0, static_cast<double>(evaluator.evaluations()) /
                                                                      static_cast<double>(max_evaluations))
                                                  : progress.fraction(1);
    shrink(planned_population(initial_, settings_.minimum_population, used_after));
}

void Lshade::update_memory(const std::vector<double>& success_f, const std::vector<double>& success_cr,
                           const std::vector<double>& improvements) {
    if (success_f.empty()) return;
    const double f_mean = weighted_lehmer_mean(success_f, improvements);
    const bool all_zero = std::all_of(success_cr.begin(), success_cr.end(), [](double c) { return c == 0.0; });
    const double cr_mean = all_zero ? terminal_cr : weighted_lehmer_mean(success_cr, improvements);
    const auto k = static_cast<std::size_t>(memory_position_);
    std::tie(memory_f_[k], memory_cr_[k]) = updated_memory(memory_f_[k], memory_cr_[k], f_mean, cr_mean);
    memory_position_ = (memory_position_ + 1) % settings_.memory_size;
}

void Lshade::update_memory() {
    update_memory(success_f_, success_cr_, improvement_);
    success_f_.clear();
    success_cr_.clear();
    improvement_.clear();
}

void Lshade::shrink(Eigen::Index target) {
    Eigen::Index n = population_.cols();
    // The worst individuals go, one at a time (the worst's last column takes its place).
    while (n > target) {
        Eigen::Index worst = 0;
        for (Eigen::Index j = 1; j < n; ++j)
            if (fitness_[j] > fitness_[worst]) worst = j;
        population_.col(worst) = population_.col(n - 1);
        fitness_[worst] = fitness_[n - 1];
        --n;
    }
    if (n == population_.cols()) return;
    population_.conservativeResize(Eigen::NoChange, n);
    fitness_.conservativeResize(n);
    // The archive shrinks with the population; members past the new size are dropped.
    archive_capacity_ = static_cast<Eigen::Index>(std::round(static_cast<double>(n) * settings_.archive_rate));
    archive_count_ = std::min(archive_count_, archive_capacity_);
}

namespace {

class PaperLshade final : public Lshade {
public:
    explicit PaperLshade(const ParameterSet& p) : Lshade(settings_from(p)) {}
};

const bool registered = register_optimizer({
    "lshade",
    "L-SHADE: SHADE with linear population size reduction (Tanabe & Fukunaga, CEC 2014)",
    {
        ParameterSpec::integer("population", 0, 0, 1'000'000, "initial population N_init; 0 = round(18 x dimension)"),
        ParameterSpec::real("archive_rate", 2.6, 0.0, 100.0, "archive size |A| = round(archive_rate x N)"),
        ParameterSpec::integer("memory_size", 6, 1, 1000, "H, entries of the success-history memory of F and CR"),
        ParameterSpec::real("p_best", 0.11, 0.0, 1.0, "p of current-to-pbest/1: pbest from the best max(2, round(p N))"),
        archive_entry_parameter(),
        ParameterSpec::boolean("sticky_terminal_cr", true,
                               "true: a CR memory slot at the terminal value stays there (the paper); false: the next "
                               "update replaces it (Tanabe's code)"),
    },
    [](const ParameterSet& p) { return std::make_unique<PaperLshade>(p); },
});

}  // namespace
}  // namespace mhb::shade

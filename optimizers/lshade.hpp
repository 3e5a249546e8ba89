#pragma once
// L-SHADE (Tanabe & Fukunaga, CEC 2014): SHADE's current-to-pbest/1/bin with an external archive and
// a success-history memory of F and CR, plus linear population size reduction. The rules that jSO
// (optimizers/jso.cpp) changes are virtual, so that jSO is this class with its changes and nothing
// copied. Equation numbers and every choice: docs/algorithms.md, "L-SHADE" and "jSO".
#include <utility>
#include <vector>

#include "framework/optimizer.hpp"
#include "framework/parameters.hpp"

namespace mhb::shade {

// The CR memory's terminal value (the paper's ⊥): CR = 0 from then on for that slot.
constexpr double terminal_cr = -1.0;

// N_{G+1} = round((N_min - N_init) * used + N_init), used = NFE / MAX_NFE (LPSR).
Eigen::Index planned_population(Eigen::Index initial, Eigen::Index minimum, double used);

// mean_WL(S) = sum w_k S_k^2 / sum w_k S_k with w_k = Δf_k / sum Δf (Δf_k > 0).
double weighted_lehmer_mean(const std::vector<double>& values, const std::vector<double>& improvements);

// What a successful trial sends to the archive. The paper: the parent it replaced; Tanabe's code (it
// copies the trial into the population before copying the population's column to the archive): the
// trial. docs/algorithms.md, "selection".
enum class ArchiveEntry { parent, trial };

struct Settings {
    Eigen::Index initial_population = 0;  // 0: the variant's rule of the dimension
    Eigen::Index minimum_population = 4;
    double archive_rate = 2.6;             // |A| = round(archive_rate * N)
    int memory_size = 6;                   // H
    double p_best = 0.11;                  // share of the population p-best is drawn from
    double initial_memory_f = 0.5;
    double initial_memory_cr = 0.5;
    ArchiveEntry archive_entry = ArchiveEntry::parent;
    // Whether a CR slot that reached ⊥ keeps it (L-SHADE's paper) or takes the next generation's mean
    // again (Tanabe's code, which resets the slot before it tests it for ⊥). docs/algorithms.md.
    bool sticky_terminal_cr = true;
};

class Lshade : public Optimizer {
public:
    explicit Lshade(Settings settings) : settings_(settings) {}

    void initialize(Evaluator& evaluator, Rng& rng) override;
    void iterate(const Progress& progress, Evaluator& evaluator, Rng& rng) override;

    Eigen::Index population_size() const { return population_.cols(); }
    const std::vector<double>& memory_f() const { return memory_f_; }
    const std::vector<double>& memory_cr() const { return memory_cr_; }
    const Matrix& population() const { return population_; }
    const Vector& fitness() const { return fitness_; }
    // The archive's members, in the order they were stored (until it is full).
    Eigen::Ref<const Matrix> archive() const { return archive_.leftCols(archive_count_); }

    // One generation's successful F, CR and improvements Δf folded into the memory slot whose turn it
    // is; the rest of the class calls it with the generation's own sets, tests with sets of their own.
    void update_memory(const std::vector<double>& success_f, const std::vector<double>& success_cr,
                       const std::vector<double>& improvements);

    // The rules jSO changes (public so that tests can check each against the papers). `used` is the share of the evaluation budget spent when the generation starts (NFE/MAX_NFE).
    virtual Eigen::Index initial_population(int dimension) const;
    // The means (mu_F, mu_CR) drawn for memory slot r.
    virtual std::pair<double, double> memory_means(int slot) const;
    virtual double adjusted_cr(double cr, double used) const;
    virtual double adjusted_f(double f, double used) const;
    // The factor of (x_pbest - x_i); the factor of the difference (x_r1 - x_r2) is always F.
    virtual double pbest_factor(double f, double used) const;
    virtual double p_best_rate(double used) const;
    virtual bool pbest_may_be_target(double used) const;
    // The new memory entries from the old ones and the weighted Lehmer means of this generation's
    // successful F and CR (cr_mean = terminal_cr when every successful CR was 0).
    virtual std::pair<double, double> updated_memory(double old_f, double old_cr, double f_mean, double cr_mean) const;

protected:
    const Settings& settings() const { return settings_; }

private:
    void make_trial(Eigen::Index i, Eigen::Index pbest, double f, double cr, double used, const Bounds& bounds, Rng& rng);
    void update_memory();
    void shrink(Eigen::Index target);

    Settings settings_;
    Eigen::Index initial_ = 0;
    Matrix population_, trials_, archive_;
    Vector fitness_, trial_fitness_;
    Eigen::Index archive_count_ = 0, archive_capacity_ = 0;
    std::vector<double> memory_f_, memory_cr_;
    int memory_position_ = 0;
    std::vector<double> f_, cr_;
    std::vector<double> success_f_, success_cr_, improvement_;
    std::vector<Eigen::Index> order_;
};

// Parameters L-SHADE and jSO share; each adds its own defaults.
Settings settings_from(const ParameterSet& p);
// `archive_entry`, which both register with the same default (the parent, as both papers).
ParameterSpec archive_entry_parameter();

}  // namespace mhb::shade

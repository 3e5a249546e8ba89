#pragma once
// A problem is a box-bounded objective that evaluates a whole population at once.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "framework/shared_problem_data.hpp"

namespace mhb {

using Vector = Eigen::VectorXd;
// A population: one candidate per column (column-major, so each candidate is contiguous).
using Matrix = Eigen::MatrixXd;

struct Bounds {
    Vector lower;
    Vector upper;
};

// Known truth about a problem, used for accuracy columns in tables.
struct KnownTruth {
    std::optional<double> optimum_value;        // the global minimum of the objective
    std::optional<Vector> true_parameters;      // the parameters the data were made with (error %)
    std::optional<Vector> reference_solution;   // an exact optimum found another way (e.g. least squares)
    std::optional<double> reference_fitness;    // objective at reference_solution
    std::string reference_label;                // what reference_solution is ("least-squares optimum")
};

class Problem {
public:
    virtual ~Problem() = default;

    int dimension() const { return static_cast<int>(bounds_.lower.size()); }
    const Bounds& bounds() const { return bounds_; }
    const std::vector<std::string>& parameter_names() const { return parameter_names_; }
    // True when the parameters mean something physical (named by the problem, not x1..xD): the
    // framework then records their convergence for parameter plots.
    bool has_named_parameters() const { return named_parameters_; }
    const KnownTruth& truth() const { return truth_; }

    // Fitness of each column of `x` into `f` (f.size() == x.cols()). Called with populations of any
    // size from many trials at once, so it must be thread-compatible (const, no shared mutable state)
    // and should not allocate per candidate.
    virtual void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const = 0;

    // Replaces the box (an experiment may narrow or widen it, as the seed paper's Table 2 does);
    // std::invalid_argument when sizes differ or lower > upper somewhere.
    void override_bounds(const Vector& lower, const Vector& upper);

protected:
    // Called after override_bounds: a problem whose known truth depends on the box (an exact
    // optimum inside it) recomputes it here.
    virtual void bounds_changed() {}

public:
    // Free text shown in `mhbench list` and reports (e.g. the data file a PMSM problem was fitted to).
    virtual std::string describe() const { return {}; }

protected:
    // Sets bounds and names (x1..xD when `names` is empty).
    void set_domain(Vector lower, Vector upper, std::vector<std::string> names = {});
    void set_domain(int dimension, double lower, double upper);
    KnownTruth truth_;

private:
    Bounds bounds_;
    std::vector<std::string> parameter_names_;
    bool named_parameters_ = false;
};

// What a problem factory may need besides its parameters.
struct ProblemContext {
    std::filesystem::path base_directory;  // relative paths in parameters resolve against this
    std::uint64_t seed = 0;                 // for problems with noise or random instances
    // Data shared by the instances of one experiment (nullptr outside an experiment: build your own).
    std::shared_ptr<SharedProblemData> shared;
};

}  // namespace mhb

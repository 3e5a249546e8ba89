#include "problems/cec/cec_suite.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>

#include <Eigen/LU>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "framework/input_error.hpp"
#include "framework/registry.hpp"
#include "problems/cec/cec_data.hpp"

namespace mhb::cec {
namespace {

using Index = Eigen::Index;
constexpr int max_dimension = 100;
constexpr double box = 100.0;
// The C code's weight of a component whose shift is exactly x.
constexpr double infinite_weight = 1.0e99;

using Population = Eigen::Ref<const Matrix>;

// The Lunacek bi-Rastrigin is the one basic function whose point is changed before the rotation:
// doubled and mirrored where o_i < 0 (the C code's tmpx).
bool mirrors_before_rotation(const Basic& b) { return b.function == &lunacek_bi_rastrigin; }
double mirror(double o_i) { return o_i < 0.0 ? -2.0 : 2.0; }

// Group sizes of a hybrid at dimension d, as the C code computes them (ceil of a double product).
std::vector<int> group_sizes(const Hybrid& h, int d) {
    std::vector<int> sizes;
    int taken = 0;
    for (std::size_t p = 0; p + 1 < h.parts.size(); ++p) {
        sizes.push_back(static_cast<int>(std::ceil(h.parts[p].second * d)));
        taken += sizes.back();
    }
    sizes.push_back(d - taken);
    return sizes;
}

// g(M (s (x - o))) of every column into `out`.
void evaluate_basic(const Basic& b, Population x, const Vector& o, const Matrix& m, bool rotated, Eigen::Ref<Vector> out) {
    const Index d = x.rows();
    Matrix u = (x.colwise() - o) * b.scale;
    if (mirrors_before_rotation(b))
        for (Index i = 0; i < d; ++i) u.row(i) *= mirror(o[i]);
    Matrix rotated_u;
    if (rotated) rotated_u.noalias() = m * u;
    const Matrix& z = rotated ? rotated_u : u;
    for (Index j = 0; j < x.cols(); ++j) out[j] = b.function(z.col(j).data(), u.col(j).data(), static_cast<int>(d));
}

// The hybrid of every column into `out`: y = (M (x - o)) shuffled by `permutation`, then each
// group of y through its basic function, scaled as that function is scaled.
void evaluate_hybrid(const Hybrid& h, const std::vector<int>& sizes, Population x, const Vector& o, const Matrix& m,
                     const std::vector<int>& permutation, Eigen::Ref<Vector> out) {
    const Index d = x.rows();
    Matrix z;
    z.noalias() = m * (x.colwise() - o);
    std::array<double, max_dimension> y, group;
    for (Index j = 0; j < x.cols(); ++j) {
        for (Index i = 0; i < d; ++i) y[static_cast<std::size_t>(i)] = z(permutation[static_cast<std::size_t>(i)], j);
        double total = 0.0;
        int start = 0;
        for (std::size_t p = 0; p < h.parts.size(); ++p) {
            const Basic& b = h.parts[p].first;
            const int n = sizes[p];
            for (int i = 0; i < n; ++i) group[static_cast<std::size_t>(i)] = y[static_cast<std::size_t>(start + i)] * b.scale;
            // Inside a hybrid the C code's global y is the whole shuffled vector: Schaffer's F7
            // reads its first n entries, not its own group's (docs/test-functions.md). The Lunacek
            // mirrors its group by the signs of the first n entries of o.
            const double* u = y.data();
            if (mirrors_before_rotation(b)) {
                for (int i = 0; i < n; ++i) group[static_cast<std::size_t>(i)] *= mirror(o[i]);
                u = group.data();
            }
            total += b.function(group.data(), u, n);
            start += n;
        }
        out[j] = total;
    }
}

class CecFunction final : public Problem {
public:
    CecFunction(const Definition& definition, int d, std::shared_ptr<const FunctionData> data)
        : definition_(definition), data_(std::move(data)) {
        set_domain(d, -box, box);
        truth_.optimum_value = definition_.optimum;
        Vector optimum = data_->shifts.front();
        if (const auto* b = std::get_if<Basic>(&definition_.formula); b && b->function == &levy_cec2017)
            // The organisers' Levy has w = 1 + (z - 1)/4, which is 1 (its minimum) at z = 1, not at
            // z = 0: the minimiser solves M (x - o) = 1, and f(o) = 901.44... at D = 10.
            optimum += data_->rotations.front().partialPivLu().solve(Vector::Ones(d));
        truth_.true_parameters = optimum;
        if (const auto* h = std::get_if<Hybrid>(&definition_.formula)) sizes_.push_back(group_sizes(*h, d));
        if (const auto* c = std::get_if<Composition>(&definition_.formula))
            for (const auto& component : *c)
                sizes_.push_back(std::holds_alternative<Hybrid>(component.g) ? group_sizes(std::get<Hybrid>(component.g), d)
                                                                            : std::vector<int>{});
    }

    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        const auto& data = *data_;
        if (const auto* b = std::get_if<Basic>(&definition_.formula)) {
            evaluate_basic(*b, x, data.shifts[0], data.rotations[0], true, f);
        } else if (const auto* h = std::get_if<Hybrid>(&definition_.formula)) {
            evaluate_hybrid(*h, sizes_[0], x, data.shifts[0], data.rotations[0], data.permutations[0], f);
        } else {
            compose(std::get<Composition>(definition_.formula), x, f);
        }
        f.array() += definition_.optimum;
    }

    std::string describe() const override { return definition_.name; }

private:
    // sum_k w_k / sum(w) * (lambda_k g_k + bias_k), with w_k = exp(-|x - o_k|^2 / (2 D sigma_k^2)) / |x - o_k|,
    // in the C code's order of operations (cf_cal).
    void compose(const Composition& c, Population x, Eigen::Ref<Vector> f) const {
        const auto& data = *data_;
        const Index n = x.cols();
        const auto d = static_cast<double>(x.rows());
        Matrix fit(static_cast<Index>(c.size()), n);
        Vector column(n);
        for (std::size_t k = 0; k < c.size(); ++k) {
            const Component& component = c[k];
            if (const auto* b = std::get_if<Basic>(&component.g))
                evaluate_basic(*b, x, data.shifts[k], data.rotations[k], component.rotated, column);
            else
                evaluate_hybrid(std::get<Hybrid>(component.g), sizes_[k], x, data.shifts[k], data.rotations[k],
                                data.permutations[k], column);
            fit.row(static_cast<Index>(k)) =
                (component.numerator * column.array() / component.denominator + component.bias).matrix().transpose();
        }
        std::array<double, 10> w;
        for (Index j = 0; j < n; ++j) {
            double w_max = 0.0, w_sum = 0.0;
            for (std::size_t k = 0; k < c.size(); ++k) {
                double distance2 = 0.0;
                for (Index i = 0; i < x.rows(); ++i) distance2 += std::pow(x(i, j) - data.shifts[k][i], 2.0);
                w[k] = distance2 != 0.0 ? std::pow(1.0 / distance2, 0.5) *
                                              std::exp(-distance2 / 2.0 / d / std::pow(c[k].sigma, 2.0))
                                        : infinite_weight;
                w_max = std::max(w_max, w[k]);
            }
            for (std::size_t k = 0; k < c.size(); ++k) w_sum += w[k];
            if (w_max == 0.0) {  // every weight underflowed: the C code weighs the components equally
                std::fill(w.begin(), w.end(), 1.0);
                w_sum = static_cast<double>(c.size());
            }
            double value = 0.0;
            for (std::size_t k = 0; k < c.size(); ++k) value += w[k] / w_sum * fit(static_cast<Index>(k), j);
            f[j] = value;
        }
    }

    const Definition& definition_;
    std::shared_ptr<const FunctionData> data_;
    std::vector<std::vector<int>> sizes_;  // group sizes per hybrid (the function's, or each component's)
};

DataRequest request_for(const std::string& suite, const Definition& def, int d, std::filesystem::path folder) {
    DataRequest r{suite, def.number, d, 1, false, std::move(folder)};
    if (std::holds_alternative<Hybrid>(def.formula)) r.shuffled = true;
    if (const auto* c = std::get_if<Composition>(&def.formula)) {
        r.components = static_cast<int>(c->size());
        r.shuffled = std::any_of(c->begin(), c->end(), [](const Component& k) { return std::holds_alternative<Hybrid>(k.g); });
    }
    return r;
}

}  // namespace

bool register_suite(const std::string& suite, const std::string& title, const std::vector<Definition>& definitions) {
    bool all = true;
    for (const Definition& def : definitions) {
        const std::string dims = fmt::format("{}", fmt::join(def.dimensions, ", "));
        std::string summary = fmt::format("{} F{}: {}, [-100,100]^D, F* = {}, D in {{{}}}", title, def.number, def.name,
                                          def.optimum, dims);
        if (!def.note.empty()) summary += "; " + def.note;
        all &= register_problem(
            {fmt::format("{}_f{}", suite, def.number), summary,
             {ParameterSpec::integer("dimension", 10, 2, max_dimension,
                                     "number of variables: one of " + dims + " (where the organisers' data define it)"),
              ParameterSpec::text("data", "",
                                  "folder holding the organisers' " + suite + "/ data (empty: the copy shipped with mhbench)")},
             [suite, &def, dims](const ParameterSet& p, const ProblemContext& context) -> std::unique_ptr<Problem> {
                 const auto d = static_cast<int>(p.integer("dimension"));
                 if (std::find(def.dimensions.begin(), def.dimensions.end(), d) == def.dimensions.end())
                     throw ParameterError("dimension", fmt::format("{}_f{} is defined for D = {} only (the organisers' data); got {}",
                                                                   suite, def.number, dims, d));
                 std::filesystem::path folder = p.text("data");
                 if (!folder.empty() && folder.is_relative()) folder = context.base_directory / folder;
                 return std::make_unique<CecFunction>(def, d, function_data(request_for(suite, def, d, folder)));
             }});
    }
    return all;
}

}  // namespace mhb::cec

#include "problems/pmsm/fit/model_fit.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>

#include <Eigen/Dense>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <fmt/format.h>

#include "framework/random.hpp"
#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "problems/pmsm/fit/packet_order_sums.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"

namespace mhb::pmsm {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

double wrap_into(double x, double lo, double hi) {
    const double width = hi - lo;
    double t = std::fmod(x - lo, width);
    if (t < 0.0) t += width;
    return lo + t;
}

// Where to evaluate a central difference: 1e-4 of the declared range either side, one-sided at a
// bound. The step is that coarse because some effects are smooth only on the scale of the noise (a
// dead-time band of a few milliamperes, where each sample enters or leaves it).
constexpr double difference_step = 1e-4;  // of the parameter's declared range

std::pair<double, double> difference_points(double x, double lo, double hi, bool periodic) {
    const double h = difference_step * (hi - lo);
    if (periodic) return {x - h, x + h};
    return {std::max(x - h, lo), std::min(x + h, hi)};
}

// Variable projection of a model on its data: for given effect parameters, the base parameters that
// minimise the squared residual (the prediction is affine in them) and that residual. The data are
// reduced a block at a time, blocks in parallel, to the normal equations of the base parameters, so
// that an evaluation keeps no row-sized array. The sums are taken about reference base values near
// the solution so that the residual sum of squares, recovered from them as a quadratic, keeps its
// digits. The reference stays fixed until its owner moves it: two effect values with the same
// prediction then get the same sum to the last bit, which an optimiser's test for a flat objective
// (a harmonic's phase at zero amplitude) relies on.
class Projection {
public:
    struct BlockSums {
        Eigen::Matrix4d gram;    // phi' phi
        Eigen::Vector4d moment;  // phi' r0, r0 = logged - offset - phi reference
        double total = 0.0;      // r0' r0
    };
    struct Workspace {
        Eigen::VectorXd values;     // all parameters; the base entries are the solution after project()
        Eigen::Vector4d reference;  // base values the sums are taken about (set by workspace() and its owner)
        std::vector<BlockSums> blocks;
    };

    explicit Projection(const SteadyStateModel& model) : model_(model), n_(model.data().size()) {}

    Eigen::Index samples() const { return n_; }

    Workspace workspace(const Eigen::VectorXd& values) const {
        Workspace w;
        w.values = values;
        w.reference = values.head<4>();
        w.blocks.resize(static_cast<std::size_t>(model_.blocks()));
        return w;
    }

    // Solves the base entries of w.values for its effect entries and returns the residual sum of
    // squares. Allocation-free after the first call: the optimiser calls it for every candidate. The
    // same result on any number of threads (fixed blocks, summed in order).
    double project(Workspace& w) const {
        const auto& data = model_.data();
        const Eigen::Vector4d reference = w.reference;
        tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, model_.blocks()), [&](const tbb::blocked_range<Eigen::Index>& range) {
            auto& scratch = model_.scratch();
            for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
                AffinePrediction& a = scratch.affine[model_.scratch_index(b)];
                const Eigen::Index first = model_.block_first(b);
                model_.predict_affine(w.values.data(), a, first);
                BlockSums& sums = w.blocks[static_cast<std::size_t>(b)];
                const Eigen::Index rows = a.rows();
                a.residual_d = data.u_d.segment(first, rows).array() - a.offset_d;
                a.residual_q = data.u_q.segment(first, rows).array() - a.offset_q;
                for (int j = 0; j < 4; ++j) {
                    a.residual_d -= reference[j] * a.phi_d.col(j);
                    a.residual_q -= reference[j] * a.phi_q.col(j);
                }
                // The 10 entries of the Gram matrix, the 4 moments and the total, on each axis.
                std::array<ColumnPair, 15> d, q;
                std::size_t k = 0;
                for (int i = 0; i < 4; ++i) {
                    for (int j = i; j < 4; ++j, ++k) {
                        d[k] = {a.phi_d.col(i).data(), a.phi_d.col(j).data()};
                        q[k] = {a.phi_q.col(i).data(), a.phi_q.col(j).data()};
                    }
                    d[k] = {a.phi_d.col(i).data(), a.residual_d.data()};
                    q[k++] = {a.phi_q.col(i).data(), a.residual_q.data()};
                }
                d[k] = {a.residual_d.data(), a.residual_d.data()};
                q[k] = {a.residual_q.data(), a.residual_q.data()};
                std::array<double, 15> on_d, on_q;
                packet_order_dots(d.data(), d.size(), rows, on_d.data());
                packet_order_dots(q.data(), q.size(), rows, on_q.data());
                k = 0;
                for (int i = 0; i < 4; ++i) {
                    for (int j = i; j < 4; ++j, ++k) sums.gram(i, j) = sums.gram(j, i) = on_d[k] + on_q[k];
                    sums.moment[i] = on_d[k] + on_q[k];
                    ++k;
                }
                sums.total = on_d[k] + on_q[k];
            }
        });
        BlockSums all{Eigen::Matrix4d::Zero(), Eigen::Vector4d::Zero(), 0.0};
        for (const auto& sums : w.blocks) {
            all.gram += sums.gram;
            all.moment += sums.moment;
            all.total += sums.total;
        }
        // Normal equations of the column-scaled regressor, solved by a pseudo-inverse so that a design
        // that does not determine all four base parameters still gives the minimum-norm step.
        Eigen::Vector4d scale, rhs;
        for (int a = 0; a < 4; ++a) {
            scale[a] = std::sqrt(all.gram(a, a));
            if (!(scale[a] > 0.0)) scale[a] = 1.0;
        }
        Eigen::Matrix4d gram;
        for (int a = 0; a < 4; ++a) {
            rhs[a] = all.moment[a] / scale[a];
            for (int b = 0; b < 4; ++b) gram(a, b) = all.gram(a, b) / (scale[a] * scale[b]);
        }
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(gram);
        const double largest = eig.eigenvalues().maxCoeff();
        Eigen::Vector4d inverse;
        for (int a = 0; a < 4; ++a) inverse[a] = eig.eigenvalues()[a] > 1e-13 * largest ? 1.0 / eig.eigenvalues()[a] : 0.0;
        const Eigen::Vector4d step =
            (eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose() * rhs).cwiseQuotient(scale);
        w.values.head<4>() = reference + step;
        return std::max(all.total - 2.0 * step.dot(all.moment) + step.dot(all.gram * step), 0.0);
    }

    // The base parameters at w.values' effect parameters by QR of the regressor, for the reported
    // values: the rows are folded in a block at a time into the triangular factor of [phi | logged -
    // offset] (Householder QR of that factor stacked on the block), so no regressor as long as the
    // data is built; the 4 x 4 problem left has the same minimisers and is solved by
    // solve_least_squares (column scaling, pivoting, minimum norm).
    Eigen::Vector4d exact_base(const Workspace& w) const {
        const auto& data = model_.data();
        using Triangle = Eigen::Matrix<double, 5, 5>;
        // Each block's own factor in parallel, then the factors folded in block order: the same
        // numbers on any number of threads.
        std::vector<Triangle> factors(static_cast<std::size_t>(model_.blocks()));
        tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, model_.blocks()), [&](const tbb::blocked_range<Eigen::Index>& range) {
            auto& scratch = model_.scratch();
            Eigen::MatrixXd stacked;
            for (Eigen::Index b = range.begin(); b != range.end(); ++b) {
                AffinePrediction& a = scratch.affine[model_.scratch_index(b)];
                const Eigen::Index first = model_.block_first(b), rows = a.rows();
                model_.predict_affine(w.values.data(), a, first);
                stacked.resize(std::max<Eigen::Index>(2 * rows, 5), 5);
                stacked.setZero();
                stacked.block(0, 0, rows, 4) = a.phi_d.matrix();
                stacked.block(rows, 0, rows, 4) = a.phi_q.matrix();
                stacked.col(4).segment(0, rows) = data.u_d.segment(first, rows) - a.offset_d.matrix();
                stacked.col(4).segment(rows, rows) = data.u_q.segment(first, rows) - a.offset_q.matrix();
                const Eigen::HouseholderQR<Eigen::MatrixXd> qr(stacked);
                factors[static_cast<std::size_t>(b)] = qr.matrixQR().topRows<5>().triangularView<Eigen::Upper>();
            }
        });
        Triangle r = Triangle::Zero();
        Eigen::Matrix<double, 10, 5> pair;
        for (const auto& factor : factors) {
            pair << r, factor;
            const Eigen::HouseholderQR<Eigen::Matrix<double, 10, 5>> qr(pair);
            r = qr.matrixQR().topRows<5>().triangularView<Eigen::Upper>();
        }
        return solve_least_squares(r.topLeftCorner<4, 4>(), r.col(4).head<4>()).solution;
    }

private:
    const SteadyStateModel& model_;
    Eigen::Index n_;
};

// The optimiser's view: the projected mean squared error as a function of the searched effect
// parameters, inside their declared plausible box.
class EffectSearch final : public Problem {
public:
    EffectSearch(const Projection& projection, const SteadyStateModel& model, Eigen::VectorXd start,
                 std::vector<Eigen::Index> searched)
        : projection_(projection), start_(std::move(start)), searched_(std::move(searched)) {
        const auto k = static_cast<Eigen::Index>(searched_.size());
        Vector lower(k), upper(k);
        std::vector<std::string> names;
        for (Eigen::Index j = 0; j < k; ++j) {
            const auto p = searched_[static_cast<std::size_t>(j)];
            lower[j] = model.bounds().lower[p];
            upper[j] = model.bounds().upper[p];
            names.push_back(model.parameter_names()[static_cast<std::size_t>(p)]);
        }
        set_domain(lower, upper, names);
    }

    void evaluate(const Eigen::Ref<const Matrix>& x, Eigen::Ref<Vector> f) const override {
        auto w = projection_.workspace(start_);  // once per population
        for (Eigen::Index c = 0; c < x.cols(); ++c) {
            w.values = start_;
            for (std::size_t j = 0; j < searched_.size(); ++j) w.values[searched_[j]] = x(static_cast<Eigen::Index>(j), c);
            f[c] = projection_.project(w) / static_cast<double>(projection_.samples());
        }
    }

private:
    const Projection& projection_;
    Eigen::VectorXd start_;
    std::vector<Eigen::Index> searched_;
};

struct ParameterInfo {
    std::vector<std::string> units;
    std::vector<bool> periodic;
};

ParameterInfo parameter_info(const SteadyStateModel& model) {
    ParameterInfo info;
    info.units = {"Ω", "H", "H", "Wb"};
    for (const auto& e : model.effects())
        for (const auto& s : e->parameter_specs())
            if (s.type == ParameterType::Real) info.units.push_back(s.unit);
    info.periodic = periodic_parameters(model);
    return info;
}

// Levenberg-Marquardt on the projected residual over the `moving` effect parameters, each kept in its
// range (angles of a full turn wrap). Each iteration reduces the rows once to the normal equations of
// all parameters (range_normal_equations) and eliminates the base parameters from them (Kaufman's
// form of variable projection: the Schur complement), so no row-sized array is kept.
//
// The Gauss-Newton matrix leaves out the residual's own curvature, which is not small when the model
// misses part of what it fits: inside a dead-time band the rows that see the band change with it, and
// the steps along the valley of voltage and band then converge only linearly (a quarter to two fifths of the gain
// left per iteration, a dozen passes over a million rows). So, as NL2SOL does (Dennis, Gay and
// Welsch 1981), a secant estimate S of the left-out term is kept from the gradients of successive
// iterations, and each step uses the Gauss-Newton matrix or it plus S, whichever predicted the last
// step's actual gain better. Leaves w at the result, its base parameters solved.
struct Polished {
    int iterations = 0;
    double rss = 0.0;  // at the result
};

class SecantPolish {
public:
    SecantPolish(const Projection& projection, const SteadyStateModel& model, Projection::Workspace& w,
                 const std::vector<Eigen::Index>& moving, const std::vector<bool>& periodic)
        : projection_(projection), model_(model), w_(w), moving_(moving), periodic_(periodic), lo_(model.bounds().lower),
          hi_(model.bounds().upper), m_(static_cast<Eigen::Index>(moving.size())),
          entries_(2.0 * static_cast<double>(projection.samples())), secant_(Eigen::MatrixXd::Zero(m_, m_)) {
        columns_.insert(columns_.end(), moving.begin(), moving.end());
    }

    Polished run() {
        rss_ = projection_.project(w_);
        if (m_ == 0) return {0, rss_};
        Eigen::VectorXd values(w_.values.size());
        int iteration = 0;
        for (; iteration < 100; ++iteration) {
            values = w_.values;
            w_.reference = values.head<4>();
            const Reduced reduced = reduce(values);
            update_secant(reduced);
            const auto step_on = unheld(values, reduced.gradient);
            double new_rss = rss_;
            const Outcome outcome = step_on.empty() ? Outcome::Failed : damped_step(reduced, step_on, values, new_rss);
            if (outcome == Outcome::Converged) break;
            if (outcome == Outcome::Failed) {
                w_.values = values;
                projection_.project(w_);
                break;
            }
            remember_step(values, reduced.gradient);
            const double gain = rss_ - new_rss;
            rss_ = new_rss;
            if (negligible(gain)) {
                ++iteration;
                break;
            }
        }
        return {iteration, rss_};
    }

private:
    // The normal equations of the moving parameters with the base parameters eliminated.
    struct Reduced {
        Eigen::MatrixXd normal;
        Eigen::VectorXd gradient;  // of half the residual's sum of squares (the residual is logged minus predicted)
    };
    enum class Outcome { Improved, Failed, Converged };

    Reduced reduce(const Eigen::VectorXd& values) const {
        const auto sums = range_normal_equations(model_, values, columns_, {0});
        const Eigen::MatrixXd& jj = sums.gram[0];
        const Eigen::VectorXd& jr = sums.moment[0];
        const Eigen::MatrixXd base_inverse = scaled_pseudo_inverse(jj.topLeftCorner(4, 4));
        const Eigen::MatrixXd cross = jj.bottomLeftCorner(m_, 4) * base_inverse;
        return {jj.bottomRightCorner(m_, m_) - cross * jj.topRightCorner(4, m_), -(jr.tail(m_) - cross * jr.head(4))};
    }

    // Dennis, Gay and Welsch's update: S s = y - A s for the step s just taken and the change y of the
    // gradient along it, after sizing S down to what that step saw of it.
    void update_secant(const Reduced& r) {
        if (last_step_.size() != m_) return;
        const Eigen::VectorXd y = r.gradient - last_gradient_;
        const double ys = y.dot(last_step_);
        if (!(ys > 0.0)) return;
        const Eigen::VectorXd left_out = y - r.normal * last_step_;
        const double sss = last_step_.dot(secant_ * last_step_);
        if (sss > 0.0) secant_ *= std::min(1.0, std::abs(last_step_.dot(left_out)) / sss);
        const Eigen::VectorXd v = left_out - secant_ * last_step_;
        secant_ += (v * y.transpose() + y * v.transpose()) / ys - (v.dot(last_step_) / (ys * ys)) * (y * y.transpose());
    }

    // The moving parameters that may step: one at a bound that the gradient pushes outward is held.
    std::vector<Eigen::Index> unheld(const Eigen::VectorXd& values, const Eigen::VectorXd& gradient) const {
        std::vector<Eigen::Index> out;
        for (Eigen::Index j = 0; j < m_; ++j) {
            const Eigen::Index p = moving_[static_cast<std::size_t>(j)];
            const bool held = !periodic_[static_cast<std::size_t>(p)] &&
                              ((values[p] <= lo_[p] && gradient[j] > 0.0) || (values[p] >= hi_[p] && gradient[j] < 0.0));
            if (!held) out.push_back(j);
        }
        return out;
    }

    // Damped steps from `values` until one lowers the residual (w_ left there, new_rss its sum of
    // squares), the Gauss-Newton step itself would gain nothing (converged), or no step helps.
    Outcome damped_step(const Reduced& r, const std::vector<Eigen::Index>& step_on, const Eigen::VectorXd& values, double& new_rss) {
        const auto f = static_cast<Eigen::Index>(step_on.size());
        const Eigen::MatrixXd a = r.normal(step_on, step_on), s = secant_(step_on, step_on);
        const Eigen::VectorXd g = r.gradient(step_on);
        // The Gauss-Newton step's predicted gain, before any trial pass over the rows.
        const Eigen::VectorXd full_step = scaled_pseudo_inverse(a) * -g;
        if (negligible(-g.dot(full_step))) return Outcome::Converged;
        const Eigen::VectorXd diagonal = a.diagonal().cwiseMax(1e-15 * a.diagonal().maxCoeff() + 1e-300);
        for (int attempt = 0; attempt < 12; ++attempt) {
            Eigen::MatrixXd damped = use_secant_ ? Eigen::MatrixXd(a + s) : a;
            damped.diagonal() += lambda_ * diagonal;
            const Eigen::LDLT<Eigen::MatrixXd> ldlt(damped);
            if (use_secant_ && !(ldlt.info() == Eigen::Success && ldlt.isPositive() && (ldlt.vectorD().array() > 0.0).all())) {
                use_secant_ = false;  // S made the model indefinite here: Gauss-Newton's alone
                --attempt;
                continue;
            }
            const Eigen::VectorXd delta = ldlt.solve(-g);
            w_.values = values;
            for (Eigen::Index k = 0; k < f; ++k) {
                const Eigen::Index p = moving_[static_cast<std::size_t>(step_on[static_cast<std::size_t>(k)])];
                place(w_.values, p, values[p] + delta[k]);
            }
            new_rss = delta.allFinite() ? projection_.project(w_) : std::numeric_limits<double>::infinity();
            if (new_rss < rss_) {
                lambda_ = std::max(lambda_ / 3.0, 1e-12);
                // Which model to trust next: the one whose predicted gain was nearer the actual.
                const double linear = -2.0 * g.dot(delta);
                const double by_normal = linear - delta.dot(a * delta), by_secant = by_normal - delta.dot(s * delta);
                const double actual = rss_ - new_rss;
                use_secant_ = std::abs(by_secant - actual) < std::abs(by_normal - actual);
                return Outcome::Improved;
            }
            lambda_ *= 4.0;
            // A failed step that stays inside the difference stencil cannot be told from the
            // Jacobian's own error: the optimum is found to the resolution the Jacobian has (on a
            // dead-time band the sum of squares is rough at that scale, and a dozen ever shorter
            // trials would each cost a pass over the rows for nothing).
            bool inside = true;
            for (Eigen::Index k = 0; k < f && inside; ++k) {
                const Eigen::Index p = moving_[static_cast<std::size_t>(step_on[static_cast<std::size_t>(k)])];
                inside = std::abs(delta[k]) <= difference_step * (hi_[p] - lo_[p]);
            }
            if (inside) break;
        }
        return Outcome::Failed;
    }

    // The step as taken (after clamping, an angle's wrap undone), for the next secant update.
    void remember_step(const Eigen::VectorXd& values, const Eigen::VectorXd& gradient) {
        Eigen::VectorXd taken = Eigen::VectorXd::Zero(m_);
        for (Eigen::Index j = 0; j < m_; ++j) {
            const Eigen::Index p = moving_[static_cast<std::size_t>(j)];
            taken[j] = w_.values[p] - values[p];
            if (periodic_[static_cast<std::size_t>(p)]) taken[j] = std::remainder(taken[j], hi_[p] - lo_[p]);
        }
        last_step_ = taken;
        last_gradient_ = gradient;
    }

    void place(Eigen::VectorXd& v, Eigen::Index p, double x) const {
        v[p] = periodic_[static_cast<std::size_t>(p)] ? wrap_into(x, lo_[p], hi_[p]) : std::clamp(x, lo_[p], hi_[p]);
    }

    // Converged when a step can gain less than 1e-8 of one unit of chi-squared (the noise variance
    // taken as rss / residual entries), which puts the parameters within about 1e-4 of their standard
    // error of the optimum: no test or interval can see the rest, and on long logs a relative
    // criterion alone would chase digits for dozens of passes over the rows.
    bool negligible(double gain) const { return gain < 1e-12 * rss_ || gain * entries_ < 1e-8 * rss_; }

    const Projection& projection_;
    const SteadyStateModel& model_;
    Projection::Workspace& w_;
    const std::vector<Eigen::Index>& moving_;
    const std::vector<bool>& periodic_;
    const Eigen::VectorXd& lo_;
    const Eigen::VectorXd& hi_;
    Eigen::Index m_;
    double entries_;
    std::vector<Eigen::Index> columns_{0, 1, 2, 3};
    // The secant part S, and the last step and gradient it is updated from.
    Eigen::MatrixXd secant_;
    Eigen::VectorXd last_step_, last_gradient_;
    bool use_secant_ = false;
    double lambda_ = 1e-3;
    double rss_ = 0.0;
};

Polished polish(const Projection& projection, const SteadyStateModel& model, Projection::Workspace& w,
                const std::vector<Eigen::Index>& moving, const std::vector<bool>& periodic) {
    return SecantPolish(projection, model, w, moving, periodic).run();
}

// A model that misses structure between segments (a shape it cannot take, an effect it lacks) is
// pulled by each segment its own way, by more than the noise would pull it: the jackknife over
// segments measures that spread, from one pass of per-segment normal equations (each segment left
// out in turn, one Gauss-Newton step from the fit on all rows). A parameter whose jackknife variance
// exceeds its model-based one beyond chance ((S - 1) times their ratio against chi-square with S - 1
// degrees of freedom, p < 0.01) gets the jackknife's variance. What it cannot pin down, the
// parameters that trade against it cannot either: its excess variance is carried to them along the
// fit's valley (a shift d of the flagged parameters moves the others by C_oF C_FF^-1 d at the least
// squares optimum, C the model-based covariance), so that a dead-time band the segments disagree on
// widens the resistance it trades with, although every segment agrees on the resistance given the
// band. Each widened interval takes t with S - 1 degrees of freedom; a well-specified fit keeps its
// intervals.
// `sums`: the per-segment normal equations of the kept parameters at `values`.
void widen_for_segment_spread(const Eigen::VectorXd& values, const std::vector<Eigen::Index>& kept, const RangeNormalEquations& sums,
                              ModelFit& fit) {
    const auto segments = fit.segments.size();
    if (segments < minimum_jackknife_segments) return;
    const Eigen::MatrixXd steps = leave_one_range_out_steps(sums);
    const auto p = static_cast<Eigen::Index>(kept.size());
    const double count = static_cast<double>(segments);
    const Eigen::MatrixXd centred = steps.colwise() - steps.rowwise().mean();
    const Eigen::MatrixXd spread = (count - 1.0) / count * centred * centred.transpose();
    const Eigen::MatrixXd& covariance = fit.uncertainty.covariance;
    const double chance = boost::math::quantile(boost::math::chi_squared(count - 1.0), 0.99);
    const double critical = boost::math::quantile(boost::math::students_t(count - 1.0), 0.975);
    fit.segment_spread.assign(fit.values.size(), false);
    std::vector<Eigen::Index> flagged;
    for (Eigen::Index c = 0; c < p; ++c) {
        const double model_se = fit.standard_error[kept[static_cast<std::size_t>(c)]];
        if (!std::isfinite(model_se) || model_se <= 0.0) continue;
        if ((count - 1.0) * spread(c, c) / (model_se * model_se) > chance) flagged.push_back(c);
    }
    if (flagged.empty() || covariance.rows() != p || !covariance.allFinite()) return;
    const auto f = static_cast<Eigen::Index>(flagged.size());
    Eigen::MatrixXd own(f, f), excess(f, f), across(p, f);
    for (Eigen::Index a = 0; a < f; ++a) {
        for (Eigen::Index b = 0; b < f; ++b) {
            own(a, b) = covariance(flagged[static_cast<std::size_t>(a)], flagged[static_cast<std::size_t>(b)]);
            excess(a, b) = spread(flagged[static_cast<std::size_t>(a)], flagged[static_cast<std::size_t>(b)]) - own(a, b);
        }
        across.col(a) = covariance.col(flagged[static_cast<std::size_t>(a)]);
    }
    // Only the directions in which the segments spread more than the noise would widen anything.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> split(excess);
    const Eigen::MatrixXd more = split.eigenvectors() * split.eigenvalues().cwiseMax(0.0).asDiagonal() * split.eigenvectors().transpose();
    const Eigen::MatrixXd carry = across * own.completeOrthogonalDecomposition().pseudoInverse();
    const Eigen::VectorXd extra = (carry * more * carry.transpose()).diagonal();
    for (Eigen::Index c = 0; c < p; ++c) {
        const Eigen::Index j = kept[static_cast<std::size_t>(c)];
        const double model_se = fit.standard_error[j];
        if (!std::isfinite(model_se) || model_se <= 0.0 || !(extra[c] > 0.0)) continue;
        const double se = std::sqrt(model_se * model_se + extra[c]);
        fit.standard_error[j] = se;
        fit.lower[j] = std::min(fit.lower[j], values[j] - critical * se);
        fit.upper[j] = std::max(fit.upper[j], values[j] + critical * se);
        fit.segment_spread[static_cast<std::size_t>(j)] = true;
    }
}

ModelFit assemble(const SteadyStateModel& model, const ModelSpec& spec, const Eigen::VectorXd& values, const FitOptions& options) {
    ModelFit fit;
    fit.spec = spec;
    fit.names = model.parameter_names();
    const auto info = parameter_info(model);
    fit.units = info.units;
    fit.periodic = info.periodic;
    fit.free = free_parameters(spec);
    fit.values = values;
    fit.range_lower = model.plausible().lower;
    fit.range_upper = model.plausible().upper;
    const Eigen::Index n = model.data().size(), p = model.parameter_count();
    fit.samples = n;
    Eigen::VectorXd residual = residual_stacked(model, values);
    fit.axis_rss = {residual.head(n).squaredNorm(), residual.tail(n).squaredNorm()};
    fit.rms = axis_rms(residual, n);
    fit.segments = segment_residuals(model.data(), residual);

    std::vector<Eigen::Index> columns;
    for (Eigen::Index j = 0; j < p; ++j)
        if (fit.free[static_cast<std::size_t>(j)]) columns.push_back(j);
    fit.lower = fit.upper = values;
    fit.standard_error = Eigen::VectorXd::Zero(p);
    for (const auto j : columns) fit.lower[j] = fit.upper[j] = fit.standard_error[j] = nan;
    if (options.intervals && !columns.empty()) {
        // A parameter that moves the prediction by less than a nanovolt over its whole range (the
        // phase of a harmonic whose amplitude is zero) is not determined at all; it is left out of
        // the covariance, which would otherwise be singular for every parameter.
        // The same pass makes the per-segment sums of the segment jackknife and of the fit's
        // leave-one-segment-out prediction (diagnosis/model_checks.hpp), which needs three segments.
        std::vector<std::vector<Eigen::Index>> partitions{{0}};
        if (fit.segments.size() >= 3) {
            partitions.emplace_back();
            for (const auto& segment : fit.segments) partitions.back().push_back(segment.first);
        }
        auto sums = partitioned_normal_equations(model, values, columns, partitions);
        const Eigen::MatrixXd& gram = sums.front().gram.front();
        std::vector<Eigen::Index> kept, kept_positions;
        for (std::size_t c = 0; c < columns.size(); ++c) {
            const Eigen::Index j = columns[c];
            const double width = fit.range_upper[j] - fit.range_lower[j];
            const auto k = static_cast<Eigen::Index>(c);
            if (j < 4 || std::sqrt(gram(k, k)) * width > 1e-9 * std::sqrt(2.0 * static_cast<double>(n))) {
                kept.push_back(j);
                kept_positions.push_back(k);
            }
        }
        if (partitions.size() > 1) {
            auto segment_sums = std::make_shared<SegmentSums>();
            segment_sums->data = &model.data();
            segment_sums->samples = n;
            segment_sums->values = values;
            segment_sums->columns = columns;
            segment_sums->starts = partitions.back();
            segment_sums->sums = std::move(sums.back());
            fit.segment_sums = std::move(segment_sums);
        }
        if (!kept.empty() && static_cast<Eigen::Index>(kept.size()) < 2 * n) {
            Eigen::VectorXd estimate(static_cast<Eigen::Index>(kept.size()));
            for (Eigen::Index c = 0; c < estimate.size(); ++c) estimate[c] = values[kept[static_cast<std::size_t>(c)]];
            // The model linearised around the estimate, a block of rows at a time: its residual is
            // the model's own.
            tbb::enumerable_thread_specific<Eigen::VectorXd> at(values);
            RegressorBlocks jacobian;
            jacobian.columns = estimate.size();
            jacobian.block_samples = SteadyStateModel::block_rows;
            jacobian.fill = [&](Eigen::Index b, Eigen::Ref<Eigen::MatrixXd> rows) {
                const Eigen::Index size = rows.rows() / 2;
                block_jacobian(model, values, kept, b, at.local(), rows.topRows(size), rows.bottomRows(size));
            };
            RowLayout layout;
            layout.samples = n;
            layout.axes = 2;
            if (model.data().has_segments()) layout.block = model.data().segment;
            fit.uncertainty = residual_uncertainty(jacobian, residual, estimate, layout, options.covariance);
            for (Eigen::Index c = 0; c < estimate.size(); ++c) {
                const Eigen::Index j = kept[static_cast<std::size_t>(c)];
                if (!std::isfinite(fit.uncertainty.standard_error[c])) continue;
                fit.standard_error[j] = fit.uncertainty.standard_error[c];
                fit.lower[j] = fit.uncertainty.lower[c];
                fit.upper[j] = fit.uncertainty.upper[c];
            }
            if (fit.segment_sums) widen_for_segment_spread(values, kept, select_columns(fit.segment_sums->sums, kept_positions), fit);
        }
    }
    if (options.keep_residual) fit.residual = std::move(residual);
    return fit;
}

std::vector<Eigen::Index> free_effect_parameters(const std::vector<bool>& free) {
    std::vector<Eigen::Index> out;
    for (std::size_t j = 4; j < free.size(); ++j)
        if (free[j]) out.push_back(static_cast<Eigen::Index>(j));
    return out;
}

ModelFit finish(const SteadyStateModel& model, const ModelSpec& spec, const Projection& projection,
                Projection::Workspace& w, const std::vector<Eigen::Index>& moving, const FitOptions& options,
                std::int64_t evaluations, std::string method) {
    const auto info = parameter_info(model);
    const int iterations = polish(projection, model, w, moving, info.periodic).iterations;
    // The base parameters once more by column-pivoting QR, for the reported values.
    w.values.head<4>() = projection.exact_base(w);
    ModelFit fit = assemble(model, spec, w.values, options);
    fit.evaluations = evaluations;
    fit.polish_iterations = iterations;
    fit.method = std::move(method);
    if (iterations > 0) fit.method += fmt::format(", then {} Levenberg-Marquardt iterations", iterations);
    return fit;
}

}  // namespace

Eigen::Index ModelFit::free_count() const {
    return static_cast<Eigen::Index>(std::count(free.begin(), free.end(), true));
}

Eigen::Index ModelFit::index_of(const std::string& name) const {
    for (std::size_t j = 0; j < names.size(); ++j)
        if (names[j] == name) return static_cast<Eigen::Index>(j);
    return -1;
}

std::vector<UnseenBias> ModelFit::unseen_biases() const {
    std::vector<UnseenBias> out;
    if (values.size() < 4) return out;
    // The bias is the law's, not the fit's: an effect made from its name says it.
    for (const auto& term : spec.effects)
        if (auto bias = make_effect(term.name)->unseen_bias(values.data()); !bias.text.empty()) out.push_back(std::move(bias));
    return out;
}

bool ModelFit::beyond_range(Eigen::Index j) const {
    if (j < 4 || !free[static_cast<std::size_t>(j)] || periodic[static_cast<std::size_t>(j)]) return false;
    const double tolerance = 1e-9 * (range_upper[j] - range_lower[j]);
    return values[j] < range_lower[j] - tolerance || values[j] > range_upper[j] + tolerance;
}

bool ModelFit::at_bound(Eigen::Index j) const {
    if (j < 4 || !free[static_cast<std::size_t>(j)]) return false;
    return at_range_end(values[j], range_lower[j], range_upper[j], periodic[static_cast<std::size_t>(j)]);
}

std::vector<bool> periodic_parameters(const SteadyStateModel& model) {
    std::vector<bool> out(4, false);
    for (const auto& e : model.effects())
        for (const auto& s : e->parameter_specs())
            if (s.type == ParameterType::Real) out.push_back(is_periodic(s));
    return out;
}

bool at_range_end(double value, double lo, double hi, bool periodic) {
    if (periodic) return false;
    const double slack = 1e-9 * (hi - lo);
    return value <= lo + slack || value >= hi - slack;
}

Eigen::VectorXd predict_stacked(const SteadyStateModel& model, const Eigen::VectorXd& values) {
    const Eigen::Index n = model.data().size();
    Eigen::VectorXd out(2 * n);
    model.predict_rows(values.data(), out.data(), out.data() + n);
    return out;
}

Eigen::VectorXd residual_stacked(const SteadyStateModel& model, const Eigen::VectorXd& values) {
    const Eigen::Index n = model.data().size();
    Eigen::VectorXd out = predict_stacked(model, values);
    out.head(n) = model.data().u_d - out.head(n);
    out.tail(n) = model.data().u_q - out.tail(n);
    return out;
}

// Base columns from the block's affine split (exact); effect columns in which the prediction is
// linear by one more prediction against the split's own at `values` (exact too), the rest by central
// differences.
void block_jacobian(const SteadyStateModel& model, const Eigen::VectorXd& values, const std::vector<Eigen::Index>& columns,
                    Eigen::Index b, Eigen::VectorXd& at, Eigen::Ref<Eigen::MatrixXd> d, Eigen::Ref<Eigen::MatrixXd> q) {
    auto& scratch = model.scratch();
    const int size = model.scratch_index(b);
    AffinePrediction& a = scratch.affine[size];
    ModelState& s = scratch.state[size];
    const Eigen::Index first = model.block_first(b);
    const auto& lo = model.bounds().lower;
    const auto& hi = model.bounds().upper;
    model.predict_affine(values.data(), a, first);
    // The prediction at `values`, made from the split when a linear column needs it, in the split's
    // scratch.
    auto& prediction_d = a.residual_d;
    auto& prediction_q = a.residual_q;
    bool have_prediction = false;
    // s holds the block's inputs at `values`' sensor-stage parameters once a column outside those
    // stages has been predicted: later columns outside them start from there.
    bool loaded = false;
    auto predict_at = [&](Eigen::Index j) {
        if (loaded && !model.in_sensor_stages(j))
            model.predict_again(at.data(), s, first);
        else
            model.predict(at.data(), s, first);
        loaded = !model.in_sensor_stages(j);
    };
    for (std::size_t c = 0; c < columns.size(); ++c) {
        const Eigen::Index j = columns[c], k = static_cast<Eigen::Index>(c);
        if (j < 4) {
            d.col(k) = a.phi_d.col(j).matrix();
            q.col(k) = a.phi_q.col(j).matrix();
            continue;
        }
        const auto [down, up] = difference_points(values[j], lo[j], hi[j], false);
        if (model.linear_in(j)) {
            if (!have_prediction) {
                prediction_d = a.offset_d + (a.phi_d.matrix() * values.head<4>()).array();
                prediction_q = a.offset_q + (a.phi_q.matrix() * values.head<4>()).array();
                have_prediction = true;
            }
            const double to = up != values[j] ? up : down;
            at[j] = to;
            predict_at(j);
            d.col(k) = ((s.u_d - prediction_d) / (to - values[j])).matrix();
            q.col(k) = ((s.u_q - prediction_q) / (to - values[j])).matrix();
            at[j] = values[j];
            continue;
        }
        at[j] = up;
        predict_at(j);
        d.col(k) = s.u_d.matrix();
        q.col(k) = s.u_q.matrix();
        at[j] = down;
        predict_at(j);
        d.col(k) = (d.col(k) - s.u_d.matrix()) / (up - down);
        q.col(k) = (q.col(k) - s.u_q.matrix()) / (up - down);
        at[j] = values[j];
    }
}

Eigen::MatrixXd prediction_jacobian(const SteadyStateModel& model, const Eigen::VectorXd& values,
                                    const std::vector<Eigen::Index>& columns) {
    const Eigen::Index n = model.data().size(), p = static_cast<Eigen::Index>(columns.size());
    Eigen::MatrixXd jacobian(2 * n, p);
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, model.blocks()), [&](const tbb::blocked_range<Eigen::Index>& blocks) {
        Eigen::VectorXd at = values;
        for (Eigen::Index b = blocks.begin(); b != blocks.end(); ++b) {
            const Eigen::Index first = model.block_first(b), rows = model.block_size(b);
            block_jacobian(model, values, columns, b, at, jacobian.block(first, 0, rows, p), jacobian.block(n + first, 0, rows, p));
        }
    });
    return jacobian;
}

Eigen::MatrixXd leave_one_range_out_steps(const RangeNormalEquations& sums) {
    const auto ranges = sums.gram.size();
    const Eigen::Index p = ranges == 0 ? 0 : sums.gram.front().rows();
    Eigen::MatrixXd all_gram = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd all_moment = Eigen::VectorXd::Zero(p);
    for (std::size_t r = 0; r < ranges; ++r) {
        all_gram += sums.gram[r];
        all_moment += sums.moment[r];
    }
    Eigen::MatrixXd steps(p, static_cast<Eigen::Index>(ranges));
    for (std::size_t r = 0; r < ranges; ++r)
        steps.col(static_cast<Eigen::Index>(r)) = scaled_pseudo_inverse(all_gram - sums.gram[r]) * (all_moment - sums.moment[r]);
    return steps;
}

RangeNormalEquations range_normal_equations(const SteadyStateModel& model, const Eigen::VectorXd& values,
                                            const std::vector<Eigen::Index>& columns, const std::vector<Eigen::Index>& starts,
                                            const Eigen::VectorXd* residual) {
    return std::move(partitioned_normal_equations(model, values, columns, {starts}, residual).front());
}

std::vector<RangeNormalEquations> partitioned_normal_equations(const SteadyStateModel& model, const Eigen::VectorXd& values,
                                                         const std::vector<Eigen::Index>& columns,
                                                         const std::vector<std::vector<Eigen::Index>>& partitions,
                                                         const Eigen::VectorXd* residual) {
    const auto& data = model.data();
    const auto p = static_cast<Eigen::Index>(columns.size());
    // Each block's share, per partition and range it touches; merged in block order so that any
    // thread count gives the same sums.
    struct Share {
        std::size_t partition = 0, range = 0;
        Eigen::MatrixXd gram;
        Eigen::VectorXd moment;
        double total = 0.0;
    };
    std::vector<std::vector<Share>> shares(static_cast<std::size_t>(model.blocks()));
    tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, model.blocks()), [&](const tbb::blocked_range<Eigen::Index>& blocks) {
        auto& scratch = model.scratch();
        Eigen::VectorXd at = values;
        // [J | r]: the Jacobian's d rows over its q rows, the residual as the last column, so that one
        // symmetric rank update per range gives J'J, J'r and r'r together.
        Eigen::MatrixXd augmented;
        Eigen::MatrixXd product(p + 1, p + 1);
        std::vector<ColumnPair> pairs_d, pairs_q;
        std::vector<double> dots_d, dots_q;
        for (Eigen::Index b = blocks.begin(); b != blocks.end(); ++b) {
            const Eigen::Index first = model.block_first(b), rows = model.block_size(b);
            augmented.resize(2 * rows, p + 1);
            block_jacobian(model, values, columns, b, at, augmented.topLeftCorner(rows, p), augmented.bottomLeftCorner(rows, p));
            // The prediction at `values` from the affine split block_jacobian left behind.
            const AffinePrediction& a = scratch.affine[model.scratch_index(b)];
            auto residual_d = augmented.col(p).head(rows), residual_q = augmented.col(p).tail(rows);
            if (residual) {
                residual_d = residual->segment(first, rows);
                residual_q = residual->segment(data.size() + first, rows);
            } else {
                residual_d = data.u_d.segment(first, rows) - a.offset_d.matrix() - a.phi_d.matrix() * values.head<4>();
                residual_q = data.u_q.segment(first, rows) - a.offset_q.matrix() - a.phi_q.matrix() * values.head<4>();
            }
            auto& out = shares[static_cast<std::size_t>(b)];
            out.clear();
            for (std::size_t partition = 0; partition < partitions.size(); ++partition) {
                const auto& starts = partitions[partition];
                // The ranges this block's rows fall in, each a run of consecutive rows.
                auto range = static_cast<std::size_t>(std::upper_bound(starts.begin(), starts.end(), first) - starts.begin() - 1);
                for (Eigen::Index k = 0; k < rows;) {
                    const Eigen::Index end =
                        range + 1 < starts.size() ? std::min(rows, starts[range + 1] - first) : rows;
                    const Eigen::Index count = end - k;
                    // The lower triangle as dot products of contiguous columns: for the few columns here
                    // a general rank update spends more time packing than multiplying.
                    pairs_d.clear();
                    pairs_q.clear();
                    for (Eigen::Index j = 0; j <= p; ++j)
                        for (Eigen::Index i = j; i <= p; ++i) {
                            const double *ci = augmented.col(i).data(), *cj = augmented.col(j).data();
                            pairs_d.push_back({ci + k, cj + k});
                            pairs_q.push_back({ci + rows + k, cj + rows + k});
                        }
                    dots_d.resize(pairs_d.size());
                    dots_q.resize(pairs_q.size());
                    packet_order_dots(pairs_d.data(), pairs_d.size(), count, dots_d.data());
                    packet_order_dots(pairs_q.data(), pairs_q.size(), count, dots_q.data());
                    std::size_t entry = 0;
                    for (Eigen::Index j = 0; j <= p; ++j)
                        for (Eigen::Index i = j; i <= p; ++i, ++entry) product(i, j) = dots_d[entry] + dots_q[entry];
                    Share share;
                    share.partition = partition;
                    share.range = range;
                    share.gram = product.topLeftCorner(p, p).selfadjointView<Eigen::Lower>();
                    share.moment = product.row(p).head(p).transpose();
                    share.total = product(p, p);
                    out.push_back(std::move(share));
                    k = end;
                    ++range;
                }
            }
        }
    });
    std::vector<RangeNormalEquations> all(partitions.size());
    for (std::size_t partition = 0; partition < partitions.size(); ++partition) {
        auto& sums = all[partition];
        const auto ranges = partitions[partition].size();
        sums.gram.assign(ranges, Eigen::MatrixXd::Zero(p, p));
        sums.moment.assign(ranges, Eigen::VectorXd::Zero(p));
        sums.total.assign(ranges, 0.0);
    }
    for (const auto& block : shares)
        for (const auto& share : block) {
            auto& sums = all[share.partition];
            sums.gram[share.range] += share.gram;
            sums.moment[share.range] += share.moment;
            sums.total[share.range] += share.total;
        }
    return all;
}

RangeNormalEquations select_columns(const RangeNormalEquations& sums, const std::vector<Eigen::Index>& positions) {
    const auto p = static_cast<Eigen::Index>(positions.size());
    RangeNormalEquations out;
    out.total = sums.total;
    for (std::size_t r = 0; r < sums.gram.size(); ++r) {
        Eigen::MatrixXd gram(p, p);
        Eigen::VectorXd moment(p);
        for (Eigen::Index a = 0; a < p; ++a) {
            moment[a] = sums.moment[r][positions[static_cast<std::size_t>(a)]];
            for (Eigen::Index b = 0; b < p; ++b) gram(a, b) = sums.gram[r](positions[static_cast<std::size_t>(a)], positions[static_cast<std::size_t>(b)]);
        }
        out.gram.push_back(std::move(gram));
        out.moment.push_back(std::move(moment));
    }
    return out;
}

AxisRms axis_rms(const Eigen::VectorXd& residual, Eigen::Index samples) {
    AxisRms r;
    if (samples == 0) return r;
    const double n = static_cast<double>(samples);
    r.d = std::sqrt(residual.head(samples).squaredNorm() / n);
    r.q = std::sqrt(residual.segment(samples, samples).squaredNorm() / n);
    r.total = std::sqrt((r.d * r.d + r.q * r.q) / 2.0);
    return r;
}

std::vector<SegmentResidual> segment_residuals(const Measurement& data, const Eigen::VectorXd& residual) {
    const Eigen::Index n = data.size();
    std::vector<SegmentResidual> out;
    Eigen::Index begin = 0;
    for (Eigen::Index k = 1; k <= n; ++k) {
        if (k < n && (!data.has_segments() || data.segment[k] == data.segment[k - 1])) continue;
        SegmentResidual s;
        s.label = data.has_segments() ? data.segment_labels[static_cast<std::size_t>(data.segment[begin])] : "all";
        s.first = begin;
        s.rows = k - begin;
        const auto d = residual.segment(begin, s.rows), q = residual.segment(n + begin, s.rows);
        const double rows = static_cast<double>(s.rows);
        s.rms.d = std::sqrt(d.squaredNorm() / rows);
        s.rms.q = std::sqrt(q.squaredNorm() / rows);
        s.rms.total = std::sqrt((s.rms.d * s.rms.d + s.rms.q * s.rms.q) / 2.0);
        s.mean = {d.mean(), q.mean()};
        out.push_back(s);
        begin = k;
    }
    return out;
}

std::vector<Eigen::Index> search_subsample(Eigen::Index rows, const FitOptions& options) {
    std::vector<Eigen::Index> out;
    if (options.search_rows <= 0 || rows <= options.search_rows) {
        out.resize(static_cast<std::size_t>(rows));
        std::iota(out.begin(), out.end(), Eigen::Index{0});
        return out;
    }
    // Selection sampling (Knuth's algorithm S): each row kept with the probability that leaves
    // exactly search_rows, in order, in one pass.
    Rng rng(derive_seed(options.seed, "search rows", "", 0));
    Eigen::Index needed = options.search_rows;
    for (Eigen::Index k = 0; k < rows && needed > 0; ++k)
        if (static_cast<double>(rows - k) * rng.uniform() < static_cast<double>(needed)) {
            out.push_back(k);
            --needed;
        }
    return out;
}

namespace {

// The listed rows of the columns `model` reads (no time, no segments, no temperature that none of its
// effects uses), for a model of a subset: the subsets a long log is polished on stay small.
Measurement model_rows(const SteadyStateModel& model, const std::vector<Eigen::Index>& rows) {
    const Measurement& data = model.data();
    Measurement out;
    out.source = data.source;
    out.current_loop_bandwidth = data.current_loop_bandwidth;
    out.current_loop_delay = data.current_loop_delay;
    // A stated loop runs along consecutive rows of a segment: the subset keeps the segments and the
    // time of its rows (a log without time: a control period a row), so that rows the subset
    // skipped break the run.
    if (data.current_loop_bandwidth > 0.0) {
        if (data.has_segments()) {
            out.segment = data.segment(rows);
            out.segment_labels = data.segment_labels;
        }
        if (data.t) {
            out.t = Eigen::VectorXd((*data.t)(rows));
        } else {
            out.t = Eigen::VectorXd(static_cast<Eigen::Index>(rows.size()));
            const double period = current_loop_period(data);
            for (std::size_t k = 0; k < rows.size(); ++k) (*out.t)[static_cast<Eigen::Index>(k)] = static_cast<double>(rows[k]) * period;
        }
    }
    out.i_d = data.i_d(rows);
    out.i_q = data.i_q(rows);
    out.u_d = data.u_d(rows);
    out.u_q = data.u_q(rows);
    out.omega_e = data.omega_e(rows);
    if (data.theta_e) out.theta_e = Eigen::VectorXd((*data.theta_e)(rows));
    if (model.reads_temp_winding()) out.temp_winding = Eigen::VectorXd((*data.temp_winding)(rows));
    if (model.reads_temp_magnet()) out.temp_magnet = Eigen::VectorXd((*data.temp_magnet)(rows));
    return out;
}

}  // namespace

ModelFit fit_model(const Measurement& data, const ModelSpec& spec, const FitOptions& options, const Eigen::VectorXd* start,
                   const std::vector<Eigen::Index>& search) {
    const auto model = make_model(spec, data);
    const auto free = free_parameters(spec);
    const Eigen::VectorXd initial = start ? *start : model->parameters_of(MotorParameters{});
    std::vector<Eigen::Index> searched = search;
    if (searched.empty() && !start) searched = free_effect_parameters(free);
    const Projection projection(*model);
    auto w = projection.workspace(initial);
    if (searched.empty())
        return finish(*model, spec, projection, w, free_effect_parameters(free), options, 0,
                      spec.effects.empty() || free_effect_parameters(free).empty() ? "linear least squares (exact)"
                                                                                   : "local refinement from the given start");

    const auto rows = search_subsample(data.size(), options);
    std::unique_ptr<SteadyStateModel> sample_model;
    std::optional<Projection> sample_projection;
    if (static_cast<Eigen::Index>(rows.size()) < data.size()) {
        sample_model = make_model(spec, model_rows(*model, rows));
        sample_projection.emplace(*sample_model);
    }
    const EffectSearch problem(sample_projection ? *sample_projection : projection, *model, initial, searched);
    const auto moving = free_effect_parameters(free);
    auto optimizer = make_optimizer(options.optimizer);
    const auto k = static_cast<std::int64_t>(searched.size());
    const std::int64_t budget = options.evaluations > 0 ? options.evaluations : 150 + 50 * k;
    const TrialRecord record = run_trial(*optimizer, problem, TrialSetup{Budget{0, budget}, options.seed, false});
    std::string method = fmt::format("{} over {} effect parameter{} ({} evaluations{})", options.optimizer, k, k == 1 ? "" : "s",
                                     record.evaluations,
                                     sample_model ? fmt::format(" on {} of the {} rows", rows.size(), data.size()) : "");
    if (!record.ok) method += " [the optimiser failed: " + record.error + "]";
    // The optimiser's best, or the start when that is better (the start is a declared typical value).
    w.values = initial;
    int polished_iterations = 0;  // before the final polish on all rows
    if (record.best_position.size() == k) {
        Eigen::VectorXd best = initial;
        for (std::size_t j = 0; j < searched.size(); ++j) best[searched[j]] = record.best_position[static_cast<Eigen::Index>(j)];
        if (!sample_projection) {
            // Both polished, as on a subsample below (the rows are few): a search that ends on the
            // plateau where a dead-time band acts as a resistance would otherwise beat the start
            // unpolished, and its polish would stay on the plateau.
            const auto periodic = parameter_info(*model).periodic;
            auto from_search = projection.workspace(best);
            const Polished search_polish = polish(projection, *model, from_search, moving, periodic);
            auto from_start = projection.workspace(initial);
            const Polished start_polish = polish(projection, *model, from_start, moving, periodic);
            const bool start_better = start_polish.rss < search_polish.rss;
            w.values = start_better ? from_start.values : from_search.values;
            polished_iterations = start_better ? start_polish.iterations : search_polish.iterations;
        } else {
            // On a subsample both are polished, where an iteration is cheap, and the better one goes
            // on: a search can miss a narrow valley (a dead-time band of milliamperes, in a box of
            // amperes whose larger part is a plateau that the base resistance absorbs), and its
            // polish would then be left to the expensive passes over all rows. Then it is polished
            // on subsets ten times larger each, up to all rows: each starts nearer the optimum of all
            // rows, so the polish on all rows needs few iterations.
            const auto periodic = parameter_info(*model).periodic;
            auto polished_on_sample = [&](const Eigen::VectorXd& from) {
                auto sample = sample_projection->workspace(from);
                return std::pair{polish(*sample_projection, *sample_model, sample, moving, periodic).rss, sample.values};
            };
            const auto [search_rss, from_search] = polished_on_sample(best);
            const auto [start_rss, from_start] = polished_on_sample(initial);
            best = start_rss < search_rss ? from_start : from_search;
            FitOptions level = options;
            for (level.search_rows = 10 * options.search_rows; level.search_rows < data.size(); level.search_rows *= 10) {
                const auto subset = make_model(spec, model_rows(*model, search_subsample(data.size(), level)));
                const Projection subset_projection(*subset);
                auto on_subset = subset_projection.workspace(best);
                polish(subset_projection, *subset, on_subset, moving, periodic);
                best = on_subset.values;
            }
            w.values = best;
        }
    }
    ModelFit fit = finish(*model, spec, projection, w, moving, options, record.evaluations, method);
    fit.polish_iterations += polished_iterations;
    return fit;
}

Eigen::VectorXd refine_parameters(const SteadyStateModel& model, const ModelSpec& spec, const Eigen::VectorXd& start) {
    const Projection projection(model);
    auto w = projection.workspace(start);
    polish(projection, model, w, free_effect_parameters(free_parameters(spec)), parameter_info(model).periodic);
    return w.values;
}

ModelFit polish_model(const Measurement& data, const ModelSpec& spec, const Eigen::VectorXd& start, const FitOptions& options) {
    const auto model = make_model(spec, data);
    const Projection projection(*model);
    auto w = projection.workspace(start);
    return finish(*model, spec, projection, w, free_effect_parameters(free_parameters(spec)), options, 0,
                  "local refinement from the given start");
}

const Eigen::VectorXd& residual_of(const Measurement& data, const ModelFit& fit, Eigen::VectorXd& storage) {
    if (fit.residual.size() == 2 * data.size()) return fit.residual;
    storage = residual_stacked(*make_model(fit.spec, data), fit.values);
    return storage;
}

}  // namespace mhb::pmsm

// The steady-state model evaluated a block of rows at a time: its split into an offset and one column
// per base parameter against predictions made one by one, for every library effect and for an effect
// that does not state how it depends on the base parameters; blocks in parallel give the same numbers
// on any number of threads; the per-range normal equations against the Jacobian; the search subsample;
// the row memo of expensive per-row functions and the per-segment sums a fit keeps, to the bit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>

#include <Eigen/Dense>
#include <tbb/task_arena.h>

#include "framework/random.hpp"
#include "problems/pmsm/fit/model_fit.hpp"
#include "problems/pmsm/model/sample_and_hold.hpp"
#include "problems/pmsm/model/steady_state_model.hpp"
#include "problems/pmsm/diagnosis/model_checks.hpp"
#include "problems/pmsm/effects/row_memo.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"

using namespace mhb;
using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

// The voltage offset's parameters with a model side that adds a constant and a term proportional to
// the resistance, without saying so: the split must take it as a general affine map.
class UnstatedOffset final : public Effect {
public:
    UnstatedOffset() : Effect("voltage_offset", ParameterSet(EffectRegistry::instance().at("voltage_offset", "effect").parameters, {})) {}
    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::LoggedVoltage); }
    void model(ModelStage, const double* p, ModelState& s) const override {
        s.u_d += p[0] + 0.3 * s.rs * s.i_q;
        s.u_q += p[1];
    }
};

// Effect values drawn inside each declared range.
Eigen::VectorXd random_values(const SteadyStateModel& model, Rng& rng) {
    Eigen::VectorXd v = model.parameters_of(MotorParameters{});
    for (Eigen::Index j = 4; j < v.size(); ++j) v[j] = rng.uniform(model.bounds().lower[j], model.bounds().upper[j]);
    return v;
}

// The offset and base columns from whole-data predictions, one per unit base vector (stacked d, q).
void reference_split(const SteadyStateModel& model, Eigen::VectorXd values, Eigen::VectorXd& offset, Eigen::MatrixXd& phi) {
    values.head<4>().setZero();
    offset = predict_stacked(model, values);
    phi.resize(offset.size(), 4);
    for (int j = 0; j < 4; ++j) {
        values.head<4>().setZero();
        values[j] = 1.0;
        phi.col(j) = predict_stacked(model, values) - offset;
    }
}

// Scales the q current at Coefficients, a stage after the sensors', with the voltage offset's
// parameters: an effect that changes the inputs of the later stages, saying so (the default) or not.
class ScaledCurrent final : public Effect {
public:
    explicit ScaledCurrent(bool says_so)
        : Effect("voltage_offset", ParameterSet(EffectRegistry::instance().at("voltage_offset", "effect").parameters, {})), says_so_(says_so) {}
    unsigned model_stages() const override { return static_cast<unsigned>(ModelStage::Coefficients); }
    bool model_changes_inputs(ModelStage) const override { return says_so_; }
    void model(ModelStage, const double* p, ModelState& s) const override { s.i_q *= 1.0 + p[0]; }

private:
    bool says_so_;
};

std::unique_ptr<SteadyStateModel> scaled_current_model(const Measurement& data, bool says_so) {
    std::vector<std::unique_ptr<Effect>> effects;
    effects.push_back(std::make_unique<ScaledCurrent>(says_so));
    return std::make_unique<SteadyStateModel>(data, std::move(effects));
}

// The current scaled by 1.2.
Eigen::VectorXd scaled_current_values(const SteadyStateModel& model) {
    Eigen::VectorXd values = model.parameters_of(MotorParameters{});
    values[4] = 0.2;
    return values;
}

// The largest difference between the split and predictions made one by one, relative to their size.
double split_error(const SteadyStateModel& model, const Eigen::VectorXd& values) {
    Eigen::VectorXd offset;
    Eigen::MatrixXd phi;
    reference_split(model, values, offset, phi);
    const Eigen::Index n = model.data().size();
    const double scale = std::max(offset.cwiseAbs().maxCoeff(), phi.cwiseAbs().maxCoeff());
    double worst = 0.0;
    for (Eigen::Index b = 0; b < model.blocks(); ++b) {
        AffinePrediction a = model.make_affine(model.block_size(b));
        const Eigen::Index first = model.block_first(b), rows = model.block_size(b);
        model.predict_affine(values.data(), a, first);
        worst = std::max(worst, (a.offset_d.matrix() - offset.segment(first, rows)).cwiseAbs().maxCoeff());
        worst = std::max(worst, (a.offset_q.matrix() - offset.segment(n + first, rows)).cwiseAbs().maxCoeff());
        worst = std::max(worst, (a.phi_d.matrix() - phi.block(first, 0, rows, 4)).cwiseAbs().maxCoeff());
        worst = std::max(worst, (a.phi_q.matrix() - phi.block(n + first, 0, rows, 4)).cwiseAbs().maxCoeff());
    }
    return worst / scale;
}

void check_split(const SteadyStateModel& model, const Eigen::VectorXd& values) { CHECK(split_error(model, values) <= 1e-12); }

}  // namespace

TEST_CASE("the affine split of each library effect's prediction equals predictions made one by one", "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({});
    REQUIRE(data.size() > SteadyStateModel::block_rows);
    REQUIRE(data.size() % SteadyStateModel::block_rows != 0);  // a shorter last block is covered
    Rng rng(11);
    for (const auto* entry : EffectRegistry::instance().entries()) {
        INFO("effect " << entry->name);
        const auto model = make_model(parse_model_spec("base+" + entry->name), data);
        for (int draw = 0; draw < 3; ++draw) check_split(*model, random_values(*model, rng));
    }
    // All at once, the order of the stages included.
    const auto all = make_model(parse_model_spec("base+current_offset+encoder_offset+rs_thermal+psi_thermal+saturation+flux_harmonic+"
                                                 "deadtime+delay+voltage_offset"),
                                data);
    for (int draw = 0; draw < 3; ++draw) check_split(*all, random_values(*all, rng));
}

TEST_CASE("the prediction is linear in each parameter an effect declares linear, beside every other library effect", "[pmsm][steady_state_model]") {
    // Three points a fifth of the range apart on a line: the middle prediction is the mean of the outer
    // two. A nonlinear parameter (the dead-time band, a harmonic's phase) fails this by far, which the
    // last check shows, so the test can tell.
    const Measurement& data = diagnosis_data({});
    Rng rng(17);
    auto curvature = [&](const SteadyStateModel& model, Eigen::Index j) {
        Eigen::VectorXd v = random_values(model, rng);
        const double lo = model.bounds().lower[j], hi = model.bounds().upper[j];
        v[j] = lo + 0.3 * (hi - lo);
        const Eigen::VectorXd a = predict_stacked(model, v);
        v[j] = lo + 0.5 * (hi - lo);
        const Eigen::VectorXd m = predict_stacked(model, v);
        v[j] = lo + 0.7 * (hi - lo);
        const Eigen::VectorXd c = predict_stacked(model, v);
        return (a + c - 2.0 * m).cwiseAbs().maxCoeff() / std::max((c - a).cwiseAbs().maxCoeff(), 1e-300);
    };
    int linear = 0;
    const auto& entries = EffectRegistry::instance().entries();
    for (const auto* entry : entries)
        for (const auto* other : entries) {
            const std::string spec = entry == other ? "base+" + entry->name : "base+" + entry->name + "+" + other->name;
            const auto model = make_model(parse_model_spec(spec), data);
            for (Eigen::Index j = 4; j < model->parameter_count(); ++j) {
                if (!model->linear_in(j)) continue;
                INFO(spec << ": " << model->parameter_names()[static_cast<std::size_t>(j)]);
                CHECK(curvature(*model, j) < 1e-9);
                ++linear;
            }
        }
    CHECK(linear > 0);
    const auto deadtime = make_model(parse_model_spec("base+deadtime"), data);
    CHECK_FALSE(deadtime->linear_in(5));
    CHECK(curvature(*deadtime, 5) > 1e-3);
}

TEST_CASE("an effect that does not state its dependence on the base parameters is split as an affine map", "[pmsm][steady_state_model]") {
    std::vector<std::unique_ptr<Effect>> effects;
    effects.push_back(std::make_unique<UnstatedOffset>());
    effects.push_back(make_effect("deadtime"));
    const SteadyStateModel model(diagnosis_data({}), std::move(effects));
    Rng rng(5);
    for (int draw = 0; draw < 3; ++draw) check_split(model, random_values(model, rng));
}

TEST_CASE("each library effect leaves the later stages' inputs as it says, and the split copies them only when one may change them",
          "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({});
    Rng rng(23);
    int asked = 0;
    for (const auto* entry : EffectRegistry::instance().entries()) {
        const auto model = make_model(parse_model_spec("base+" + entry->name), data);
        const Effect& effect = *model->effects().front();
        const Eigen::VectorXd values = random_values(*model, rng);
        for (unsigned bit = static_cast<unsigned>(ModelStage::Coefficients); bit <= static_cast<unsigned>(ModelStage::CurrentRipple); bit <<= 1) {
            const auto stage = static_cast<ModelStage>(bit);
            if (!acts_in(effect.model_stages(), stage) || effect.model_changes_inputs(stage)) continue;
            INFO("effect " << entry->name << ", stage bit " << bit);
            ModelState s = model->make_state(model->block_size(0));
            model->predict(values.data(), s, 0);
            const ModelState before = s;
            effect.model(stage, values.data() + model->parameter_offset(0), s);
            for (auto [now, then] : {std::pair{&s.i_d, &before.i_d}, std::pair{&s.i_q, &before.i_q}, std::pair{&s.omega, &before.omega},
                                     std::pair{&s.theta, &before.theta}, std::pair{&s.cos_theta, &before.cos_theta},
                                     std::pair{&s.sin_theta, &before.sin_theta}, std::pair{&s.temp_winding, &before.temp_winding},
                                     std::pair{&s.temp_magnet, &before.temp_magnet}}) {
                REQUIRE(now->size() == then->size());
                // Bit for bit (NaN included); an empty column (no temperature logged) has no data to compare.
                if (now->size() > 0)
                    CHECK(std::memcmp(now->data(), then->data(), static_cast<std::size_t>(now->size()) * sizeof(double)) == 0);
            }
            ++asked;
        }
    }
    CHECK(asked >= 9);
    // With the loop stated, dead time and flux harmonics run through it (run_through_loop rather than
    // their model()): the lanes that share the inputs still split exactly.
    Measurement looped = data;
    state_current_loop(looped, DriveTiming{1e-4, 0.0, 0.0, 250.0});
    const auto through = make_model(parse_model_spec("base+deadtime+flux_harmonic+saturation+voltage_offset"), looped);
    const auto direct = make_model(parse_model_spec("base+deadtime+flux_harmonic+saturation+voltage_offset"), data);
    const Eigen::VectorXd defaults = through->parameters_of(MotorParameters{});
    CHECK((predict_stacked(*through, defaults) - predict_stacked(*direct, defaults)).cwiseAbs().maxCoeff() > 1e-6);  // the loop acts
    for (int draw = 0; draw < 3; ++draw) check_split(*through, random_values(*through, rng));
    // An effect that changes an input after the sensors: said, the split copies the inputs back before
    // each of its runs and is exact; left unsaid, the runs compound the change and the split is wrong.
    for (const bool says_so : {true, false}) {
        const auto model = scaled_current_model(data, says_so);
        INFO("says so: " << says_so);
        CHECK((split_error(*model, scaled_current_values(*model)) <= 1e-12) == says_so);
    }
}

TEST_CASE("a block predicted again from the inputs it holds is the prediction made afresh, to the bit", "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({});
    Rng rng(29);
    auto same = [](const ModelState& a, const ModelState& b) {
        return std::memcmp(a.u_d.data(), b.u_d.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0 &&
               std::memcmp(a.u_q.data(), b.u_q.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
    };
    // Each parameter outside the sensor stages changed in turn, on a model with effects in every stage.
    const auto model = make_model(parse_model_spec("base+current_offset+encoder_offset+rs_thermal+psi_thermal+saturation+flux_harmonic+"
                                                   "deadtime+delay+voltage_offset"),
                                  data);
    const Eigen::Index b = model->blocks() - 1, first = model->block_first(b);
    int changed = 0;
    for (Eigen::Index j = 0; j < model->parameter_count(); ++j) {
        if (model->in_sensor_stages(j)) continue;
        INFO(model->parameter_names()[static_cast<std::size_t>(j)]);
        Eigen::VectorXd values = random_values(*model, rng);
        ModelState again = model->make_state(model->block_size(b)), afresh = model->make_state(model->block_size(b));
        model->predict(values.data(), again, first);
        values[j] = j < 4 ? 1.1 * values[j] : rng.uniform(model->bounds().lower[j], model->bounds().upper[j]);
        model->predict_again(values.data(), again, first);
        model->predict(values.data(), afresh, first);
        CHECK(same(again, afresh));
        ++changed;
    }
    CHECK(changed >= 15);
    // And with the loop stated, whose runs start at the block's first row.
    Measurement looped = data;
    state_current_loop(looped, DriveTiming{1e-4, 0.0, 0.0, 250.0});
    const auto through = make_model(parse_model_spec("base+deadtime+flux_harmonic+saturation"), looped);
    for (Eigen::Index j = 4; j < through->parameter_count(); ++j) {
        INFO("loop stated: " << through->parameter_names()[static_cast<std::size_t>(j)]);
        Eigen::VectorXd values = random_values(*through, rng);
        ModelState again = through->make_state(through->block_size(0)), afresh = through->make_state(through->block_size(0));
        through->predict(values.data(), again, 0);
        values[j] = rng.uniform(through->bounds().lower[j], through->bounds().upper[j]);
        through->predict_again(values.data(), again, 0);
        through->predict(values.data(), afresh, 0);
        CHECK(same(again, afresh));
    }
    // An effect that changes an input after the sensors: said, the block is loaded again and the
    // prediction is the fresh one; left unsaid, the change compounds and it is not.
    for (const bool says_so : {true, false}) {
        const auto scaled = scaled_current_model(data, says_so);
        const Eigen::VectorXd values = scaled_current_values(*scaled);
        ModelState again = scaled->make_state(scaled->block_size(0)), afresh = scaled->make_state(scaled->block_size(0));
        scaled->predict(values.data(), again, 0);
        scaled->predict_again(values.data(), again, 0);
        scaled->predict(values.data(), afresh, 0);
        INFO("says so: " << says_so);
        CHECK(same(again, afresh) == says_so);
    }
}

TEST_CASE("the search box holds the plausible range, stretched where it reaches beyond the declared one", "[pmsm][steady_state_model]") {
    const Measurement& servo = diagnosis_data({});
    const double largest = std::sqrt((servo.i_d.array().square() + servo.i_q.array().square()).maxCoeff());
    const auto small = make_model(parse_model_spec("base+deadtime"), servo);
    const Eigen::Index band = 5;
    REQUIRE(small->parameter_names()[band] == "deadtime.current_band");
    // The servo's band: plausible to 0.2 of its largest current, searched over the declared 10 A.
    CHECK(small->plausible().upper[band] == Approx(0.2 * largest));
    CHECK(small->bounds().upper[band] == 10.0);
    // The same log at a thousand times the current: 0.2 of it is beyond the declared 10 A, so the
    // box stretches to twice the plausible end and a fit can still land beyond it.
    Measurement large = servo;
    large.i_d *= 1000.0;
    large.i_q *= 1000.0;
    const auto traction = make_model(parse_model_spec("base+deadtime"), large);
    CHECK(traction->plausible().upper[band] == Approx(200.0 * largest));
    CHECK(traction->bounds().upper[band] == Approx(400.0 * largest));
    CHECK(traction->bounds().lower[band] == 0.0);
    // A parameter whose plausible range stays inside the declared one keeps the declared box.
    CHECK(traction->bounds().upper[4] == small->bounds().upper[4]);
}

TEST_CASE("predictions and fits are the same numbers on one thread and on several", "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({{"deadtime", {}}, {"flux_harmonic", {}}});
    const auto spec = parse_model_spec("base+deadtime+flux_harmonic");
    const auto model = make_model(spec, data);
    const Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    auto on = [&](int threads, auto&& work) {
        tbb::task_arena arena(threads);
        return arena.execute(work);
    };
    const Eigen::VectorXd one = on(1, [&] { return predict_stacked(*model, values); });
    const Eigen::VectorXd two = on(2, [&] { return predict_stacked(*model, values); });
    CHECK(one == two);
    ModelState whole = model->make_state();
    model->predict(values.data(), whole);
    CHECK(one.head(data.size()) == whole.u_d.matrix());
    CHECK(one.tail(data.size()) == whole.u_q.matrix());

    FitOptions options;
    options.search_rows = 400;  // the subsample path too
    const ModelFit fit1 = on(1, [&] { return fit_model(data, spec, options); });
    const ModelFit fit2 = on(2, [&] { return fit_model(data, spec, options); });
    CHECK(fit1.values == fit2.values);
    CHECK(fit1.residual == fit2.residual);
    CHECK(fit1.standard_error.isApprox(fit2.standard_error, 0.0));
}

TEST_CASE("the per-range normal equations are the Jacobian's, range by range", "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({{"delay", {}}});
    const auto model = make_model(parse_model_spec("base+delay+voltage_offset"), data);
    const Eigen::VectorXd values = model->parameters_of(MotorParameters{});
    const std::vector<Eigen::Index> columns{0, 1, 2, 3, 4, 5, 6};
    const std::vector<Eigen::Index> starts{0, 100, 777, 778, data.size() - 3};
    const auto sums = range_normal_equations(*model, values, columns, starts);
    const Eigen::MatrixXd jacobian = prediction_jacobian(*model, values, columns);
    const Eigen::Index n = data.size();
    Eigen::VectorXd y(2 * n);
    y << data.u_d, data.u_q;
    const Eigen::VectorXd residual = y - predict_stacked(*model, values);
    for (std::size_t r = 0; r < starts.size(); ++r) {
        INFO("range " << r);
        const Eigen::Index first = starts[r], rows = (r + 1 < starts.size() ? starts[r + 1] : n) - first;
        Eigen::MatrixXd j(2 * rows, 7);
        j << jacobian.middleRows(first, rows), jacobian.middleRows(n + first, rows);
        Eigen::VectorXd e(2 * rows);
        e << residual.segment(first, rows), residual.segment(n + first, rows);
        const Eigen::MatrixXd gram = j.transpose() * j;
        CHECK((sums.gram[r] - gram).cwiseAbs().maxCoeff() <= 1e-9 * gram.cwiseAbs().maxCoeff());
        CHECK((sums.moment[r] - j.transpose() * e).cwiseAbs().maxCoeff() <= 1e-9 * (j.transpose() * e).cwiseAbs().maxCoeff() + 1e-15);
        CHECK(sums.total[r] == Approx(e.squaredNorm()).epsilon(1e-12));
    }
}

TEST_CASE("held-out segment errors of a model linear in its parameters equal exact refits without the segment", "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({{"voltage_offset", {{"u_d", 0.02}, {"u_q", -0.01}}}});
    const auto spec = parse_model_spec("base+voltage_offset");
    const auto fit = fit_model(data, spec, FitOptions{});
    const auto folds = leave_one_segment_out(data, spec, fit.values);
    const auto model = make_model(spec, data);
    const std::vector<Eigen::Index> all{0, 1, 2, 3, 4, 5};
    const Eigen::MatrixXd phi = prediction_jacobian(*model, fit.values, all);  // the model is this regression
    const Eigen::Index n = data.size();
    REQUIRE(folds.size() == fit.segments.size());
    for (std::size_t s = 0; s < fit.segments.size(); ++s) {
        const auto& seg = fit.segments[s];
        std::vector<Eigen::Index> train, test;
        for (int axis = 0; axis < 2; ++axis)
            for (Eigen::Index k = 0; k < n; ++k) (k >= seg.first && k < seg.first + seg.rows ? test : train).push_back(axis * n + k);
        Eigen::MatrixXd a(static_cast<Eigen::Index>(train.size()), 6);
        Eigen::VectorXd y(a.rows());
        for (std::size_t r = 0; r < train.size(); ++r) {
            a.row(static_cast<Eigen::Index>(r)) = phi.row(train[r]);
            y[static_cast<Eigen::Index>(r)] = train[r] < n ? data.u_d[train[r]] : data.u_q[train[r] - n];
        }
        const Eigen::VectorXd theta = a.colPivHouseholderQr().solve(y);
        double sse = 0.0;
        for (const auto row : test) {
            const double logged = row < n ? data.u_d[row] : data.u_q[row - n];
            sse += std::pow(logged - phi.row(row).dot(theta), 2);
        }
        INFO("segment " << seg.label);
        CHECK(folds[s] == Approx(sse).epsilon(1e-7));
    }
}

TEST_CASE("the search subsample is every row of short data and a uniform random subset of long data", "[pmsm][model_fit]") {
    FitOptions options;
    options.search_rows = 300;
    const auto all = search_subsample(300, options);
    REQUIRE(all.size() == 300);
    CHECK(all.back() == 299);
    options.seed = 3;
    const auto some = search_subsample(1000, options);
    REQUIRE(some.size() == 300);
    CHECK(std::is_sorted(some.begin(), some.end()));
    CHECK(std::set<Eigen::Index>(some.begin(), some.end()).size() == 300);
    CHECK(some.front() >= 0);
    CHECK(some.back() < 1000);
    CHECK(search_subsample(1000, options) == some);
    options.seed = 4;
    CHECK(search_subsample(1000, options) != some);
    // Each row is kept with probability 0.3: per tenth of the rows, over 400 seeds, the count is
    // binomial(400 * 100, 0.3), mean 12 000, standard deviation 92.
    std::vector<int> per_tenth(10, 0);
    for (std::uint64_t seed = 1; seed <= 400; ++seed) {
        options.seed = seed;
        for (const auto k : search_subsample(1000, options)) ++per_tenth[static_cast<std::size_t>(k / 100)];
    }
    for (const int count : per_tenth) CHECK(std::abs(count - 12000) < 5 * 92);
    options.search_rows = 0;
    CHECK(search_subsample(5000, options).size() == 5000);
}

TEST_CASE("a search on a subsample finds the optimum a search on all rows finds", "[pmsm][model_fit]") {
    struct Case {
        std::string effect;
        std::map<std::string, ParameterValue> values;
        bool exact;  // the steady-state model is exact for the averaged plant with this effect
    };
    for (const auto& c : std::vector<Case>{{"delay", {{"tau", 1.7e-4}}, true},
                                           {"encoder_offset", {{"offset", 0.03}}, true},
                                           {"deadtime", {{"voltage", 0.3}, {"current_band", 0.02}}, false}}) {
        INFO("effect " << c.effect);
        auto spec = read_simulation_profile(profile_path("diagnosis_profile.toml"));
        spec.noise = SensorNoise{};
        spec.effects.clear();
        spec.effects.push_back(make_effect(c.effect, c.values));
        const auto data = simulate(spec).data;
        FitOptions options;
        options.search_rows = 0;
        const auto everywhere = fit_model(data, parse_model_spec("base+" + c.effect), options);
        options.search_rows = 200;
        const auto sampled = fit_model(data, parse_model_spec("base+" + c.effect), options);
        CHECK(sampled.method.find("on 200 of the") != std::string::npos);
        CHECK(everywhere.method.find("of the") == std::string::npos);
        // Where the model is exact the optimum is sharp and both polishes end on it to 1e-6. The dead
        // time's is flat (the steady-state model misses the ripple its harmonics drive, 6.8 mV rms
        // here): measured 2026-11-27, the two ends differ by 2.7e-6 in the voltage and 4e-9 in the
        // sum of squares, so that is what "the same optimum" can mean there.
        const double tolerance = c.exact ? 1e-6 : 1e-5;
        for (Eigen::Index j = 0; j < sampled.values.size(); ++j) CHECK(sampled.values[j] == Approx(everywhere.values[j]).epsilon(tolerance));
        CHECK(sampled.rss() == Approx(everywhere.rss()).epsilon(1e-7));
        const auto truth = make_effect(c.effect, c.values);
        if (c.exact)
            for (Eigen::Index j = 0; j < truth->values().size(); ++j) CHECK(sampled.values[4 + j] == Approx(truth->values()[j]).epsilon(1e-6));
    }
}

TEST_CASE("a row memo gives the function's own value, computing only rows whose argument or parameter changed bit for bit", "[pmsm][steady_state_model]") {
    RowMemo<double> memo;
    int calls = 0;
    auto compute = [&](double x) {
        ++calls;
        return 1.0 / x;  // 1 / -0 and 1 / +0 differ: a memo that took them for one argument would show it
    };
    std::vector<double> args{1.0, 2.0, +0.0, 4.0};
    auto argument = [&](Eigen::Index j) { return args[static_cast<std::size_t>(j)]; };
    const double* first = memo.of(0.5, 4, argument, compute);
    CHECK(calls == 4);
    CHECK(first[1] == 0.5);
    memo.of(0.5, 4, argument, compute);
    CHECK(calls == 4);  // all remembered
    args[2] = -0.0;
    args[3] = 5.0;
    const double* changed = memo.of(0.5, 4, argument, compute);
    CHECK(calls == 6);
    CHECK(std::signbit(changed[2]));
    CHECK(changed[3] == 0.2);
    memo.of(0.25, 4, argument, compute);  // another parameter: its own slot
    memo.of(0.75, 4, argument, compute);
    CHECK(calls == 14);
    memo.of(0.5, 4, argument, compute);  // still one of the three slots
    CHECK(calls == 14);
    memo.of(1.0, 4, argument, compute);  // a fourth replaces the least recently used (0.25)
    memo.of(0.25, 4, argument, compute);
    CHECK(calls == 22);
}

TEST_CASE("a fit's kept per-segment sums give its held-out errors and jackknife to the bit", "[pmsm][steady_state_model]") {
    const Measurement& data = diagnosis_data({{"deadtime", {{"voltage", 0.3}, {"current_band", 0.02}}}});
    const auto spec = parse_model_spec("base+deadtime+saturation");
    const auto fit = fit_model(data, spec, FitOptions{});
    REQUIRE(fit.segment_sums != nullptr);
    const auto kept = leave_one_segment_out(data, fit);
    const auto made = leave_one_segment_out(data, spec, fit.values);
    REQUIRE(kept.size() == made.size());
    for (std::size_t s = 0; s < kept.size(); ++s) CHECK(kept[s] == made[s]);
    // Any subset of the columns is the numbers a pass for those columns alone gives.
    const auto model = make_model(spec, data);
    const std::vector<Eigen::Index> subset{0, 2, 3, 5, 7};
    std::vector<Eigen::Index> positions;
    for (const auto j : subset)
        positions.push_back(std::find(fit.segment_sums->columns.begin(), fit.segment_sums->columns.end(), j) - fit.segment_sums->columns.begin());
    for (const auto k : positions) REQUIRE(k < static_cast<Eigen::Index>(fit.segment_sums->columns.size()));
    const auto selected = select_columns(fit.segment_sums->sums, positions);
    const auto alone = range_normal_equations(*model, fit.values, subset, fit.segment_sums->starts);
    for (std::size_t r = 0; r < alone.gram.size(); ++r) {
        CHECK((selected.gram[r].array() == alone.gram[r].array()).all());
        CHECK((selected.moment[r].array() == alone.moment[r].array()).all());
        CHECK(selected.total[r] == alone.total[r]);
    }
}

// The diagnosis report of a raw log (no segment column): the plot of the log with the steady windows
// found in it shaded, checked through the files gnuplot drew it from: the windows it shades are those
// of the JSON's operating_points, a log longer than the plot's pixel columns is drawn from each
// column's extremes so that a one-row spike keeps its height, and a log with a segment column gets
// no such plot.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "tests/gnuplot_data_rows.hpp"
#include "tests/pmsm_diagnosis_fixture.hpp"
#include "tests/temporary_directory.hpp"

using namespace mhb::pmsm;
using namespace mhb::pmsm::testing;

namespace {

struct ListedWindow {
    std::string label;
    long first_row = 0, rows = 0;
    double x_first = 0.0, x_last = 0.0;
};

std::vector<ListedWindow> listed_windows(const std::filesystem::path& file) {
    std::ifstream in(file);
    std::vector<ListedWindow> out;
    for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream fields(line);
        ListedWindow w;
        fields >> w.label >> w.first_row >> w.rows >> w.x_first >> w.x_last;
        out.push_back(w);
    }
    return out;
}

std::size_t occurrences(const std::string& text, const std::string& what) {
    std::size_t count = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++count;
    return count;
}

}  // namespace

TEST_CASE("a raw log's report shows the log with the windows of its operating_points shaded", "[pmsm][operating_points][cli][plots]") {
    mhb::testing::TemporaryDirectory dir;
    auto spec = read_simulation_profile(profile_path("raw_bench_log.toml"));
    auto log = simulate(spec).data;
    REQUIRE_FALSE(log.has_segments());
    REQUIRE(log.size() > 2000);
    // A one-row spike on u_d inside the log's first settled stretch, three times the log's largest
    // voltage: thinning the log for the plot would lose it; the plot must keep it.
    const Eigen::Index spike_row = 1800;
    const double spike = 3.0 * log.u_d.cwiseAbs().maxCoeff();
    log.u_d[spike_row] = spike;
    const auto csv = dir.path() / "raw.csv";
    write_measurement(csv, log);
    const auto json_path = dir.path() / "diagnosis.json", report = dir.path() / "report";
    const auto run = run_mhbench("diagnose --data " + csv.string() + " --model base --json " + json_path.string() + " --report " + report.string(),
                                 dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    const auto j = nlohmann::json::parse(mhb::testing::read_file(json_path));
    const auto& found = j["operating_points"];
    REQUIRE(found["found_automatically"] == true);
    const auto& windows = found["steady_windows"];
    REQUIRE(windows.size() >= 2);

    // report.md shows the plot, with its caption naming the method, its bandwidth and the counts.
    REQUIRE(std::filesystem::exists(report / "operating_points.png"));
    REQUIRE(std::filesystem::exists(report / "operating_points.svg"));
    const std::string md = mhb::testing::read_file(report / "report.md");
    const std::regex image(R"(!\[([^\]]*)\]\(operating_points\.png\))");
    std::smatch caption;
    REQUIRE(std::regex_search(md, caption, image));
    const std::string text = caption[1].str();
    CHECK(text.find("moving-sum (MOSUM) change-point test") != std::string::npos);
    CHECK(text.find(fmt::format("bandwidth of {} rows a side", found["bandwidth_rows"].get<long>())) != std::string::npos);
    CHECK(text.find(fmt::format("{} steady windows", windows.size())) != std::string::npos);
    CHECK(text.find(fmt::format("{} of {} rows dropped as transient", found["transient_rows"].get<long>(), found["rows"].get<long>())) !=
          std::string::npos);
    CHECK(md.find("## Operating points found in the log") < md.find("## What the diagnosis says"));
    CHECK(mhb::testing::read_file(report / "report.html").find(text) != std::string::npos);

    // The windows the plot shades are the JSON's, with their times.
    const auto listed = listed_windows(report / "plot-data" / "operating_points_windows.dat");
    REQUIRE(listed.size() == windows.size());
    for (std::size_t w = 0; w < listed.size(); ++w) {
        CHECK(listed[w].label == fmt::format("\"steady{}\"", w + 1));
        CHECK(listed[w].first_row == windows[w]["first_row"].get<long>());
        CHECK(listed[w].rows == windows[w]["rows"].get<long>());
        CHECK(listed[w].x_first == Approx((*log.t)[listed[w].first_row - 1]));
        CHECK(listed[w].x_last == Approx((*log.t)[listed[w].first_row + listed[w].rows - 2]));
    }
    // One light-green rectangle a window, and one label, in each of the script's two renderings (PNG, SVG).
    const std::string script = mhb::testing::read_file(report / "plot-data" / "operating_points.gp");
    CHECK(occurrences(script, "fc rgb '#cfe8cf'") == 2 * windows.size());
    CHECK(occurrences(script, "'steady") == 2 * windows.size());

    // The log is drawn as 1000 columns of extremes: 2000 lines, the spike among them, and every
    // channel's range that of the log.
    const auto drawn = mhb::testing::data_rows(report / "plot-data" / "operating_points_log.dat");
    REQUIRE(drawn.size() == 2000);
    const std::vector<const Eigen::VectorXd*> channels{&log.i_d, &log.i_q, &log.omega_e, &log.u_d, &log.u_q};
    for (std::size_t c = 0; c < channels.size(); ++c) {
        double low = INFINITY, high = -INFINITY;
        for (const auto& row : drawn) {
            low = std::min(low, row[c + 1]);
            high = std::max(high, row[c + 1]);
        }
        CHECK(low == Approx(channels[c]->minCoeff()).epsilon(1e-5));
        CHECK(high == Approx(channels[c]->maxCoeff()).epsilon(1e-5));
    }
    CHECK(std::any_of(drawn.begin(), drawn.end(), [&](const auto& row) { return row[4] == Approx(spike).epsilon(1e-5); }));
}

TEST_CASE("without a time column the raw log's plot runs over rows counted from 1", "[pmsm][operating_points][cli][plots]") {
    mhb::testing::TemporaryDirectory dir;
    auto log = simulate(read_simulation_profile(profile_path("raw_bench_log.toml"))).data;
    log.t.reset();
    const auto csv = dir.path() / "raw.csv";
    write_measurement(csv, log);
    const auto report = dir.path() / "report";
    const auto run = run_mhbench("diagnose --data " + csv.string() + " --model base --report " + report.string(), dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    const auto listed = listed_windows(report / "plot-data" / "operating_points_windows.dat");
    REQUIRE_FALSE(listed.empty());
    for (const auto& w : listed) {
        CHECK(w.x_first == static_cast<double>(w.first_row));
        CHECK(w.x_last == static_cast<double>(w.first_row + w.rows - 1));
    }
    CHECK(mhb::testing::read_file(report / "plot-data" / "operating_points.gp").find("set xlabel 'row'") != std::string::npos);
}

TEST_CASE("a log with a segment column gets no plot of found operating points", "[pmsm][operating_points][cli][plots]") {
    mhb::testing::TemporaryDirectory dir;
    const auto csv = dir.path() / "steady.csv";
    write_measurement(csv, diagnosis_data({}));
    const auto report = dir.path() / "report";
    const auto run = run_mhbench("diagnose --data " + csv.string() + " --model base --report " + report.string(), dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    CHECK_FALSE(std::filesystem::exists(report / "operating_points.png"));
    CHECK(mhb::testing::read_file(report / "report.md").find("Operating points found") == std::string::npos);
}

TEST_CASE("a long record's residual plots are drawn from each run's extremes, a one-row spike kept", "[pmsm][cli][plots]") {
    // The averaged servo with 2500 rows an operating point: 22 500 rows, beyond the 20 000 a residual
    // plot shows row by row. Written whole, a million-row record made SVGs of 200 MB each.
    mhb::testing::TemporaryDirectory dir;
    auto spec = read_simulation_profile(profile_path("diagnosis_profile.toml"));
    for (auto& segment : spec.segments) segment.samples = 2500;
    auto log = simulate(spec).data;
    REQUIRE(log.size() > 20000);
    const Eigen::Index spike_row = log.size() / 2 + 17;
    const double spike = 3.0 * log.u_d.cwiseAbs().maxCoeff();
    log.u_d[spike_row] = spike;
    const auto csv = dir.path() / "long.csv", report = dir.path() / "report";
    write_measurement(csv, log);
    const auto run = run_mhbench("diagnose --data " + csv.string() + " --model base --report " + report.string(), dir.path() / "log");
    INFO(run.output);
    REQUIRE(run.exit_code == 0);
    for (const char* plot : {"residual_time", "residual_angle"}) {
        INFO(plot);
        const auto drawn = mhb::testing::data_rows(report / "plot-data" / (std::string(plot) + ".dat"));
        CHECK(drawn.size() <= 4000);
        CHECK(drawn.size() >= 2000);
        // The spike's residual is about the spike itself (the model predicts a few volts there).
        double highest = -INFINITY;
        for (const auto& row : drawn) highest = std::max(highest, row[1]);
        CHECK(highest > 0.5 * spike);
    }
    CHECK(mhb::testing::read_file(report / "plot-data" / "residual_time.gp").find("with lines") != std::string::npos);
}

#include <catch2/catch.hpp>

#include <sstream>

#include "framework/report_tables.hpp"

using namespace mhb;

namespace {
TrialRecord trial(const std::string& opt, std::int64_t t, double f, Vector x, bool ok = true) {
    TrialRecord r;
    r.optimizer = opt;
    r.problem = "P";
    r.trial = t;
    r.ok = ok;
    r.best_fitness = f;
    r.best_position = std::move(x);
    r.evaluations = 100;
    r.seconds = 0.5;
    return r;
}

std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) out.push_back(cell);
    if (!line.empty() && line.back() == ',') out.push_back("");
    return out;
}
}  // namespace

TEST_CASE("the CSV table holds the statistics of the trials", "[report_tables]") {
    ExperimentInfo info;
    info.name = "t";
    info.trials = 3;
    PluginVariant a, b;
    a.label = "A";
    b.label = "B";
    info.optimizers = {a, b};
    ProblemInfo p;
    p.label = "P";
    p.dimension = 2;
    p.parameter_names = {"Rs", "psi"};
    p.named_parameters = true;
    p.truth.optimum_value = 1.0;
    p.truth.true_parameters = Vector::Constant(2, 2.0);
    info.problems = {p};
    info.baseline = "A";
    info.references = {"A"};
    Vector x1(2), x2(2), x3(2);
    x1 << 1.0, 2.0;
    x2 << 3.0, 2.0;
    x3 << 2.0, 2.0;
    std::vector<TrialRecord> records{trial("A", 0, 2.0, x1), trial("A", 1, 4.0, x2), trial("A", 2, 9.0, x3, false),
                                     trial("B", 0, 1.5, x3), trial("B", 1, 1.25, x3), trial("B", 2, 1.0, x3)};
    const auto csv = csv_table(info, records);
    std::stringstream ss(csv);
    std::string header, row_a, row_b;
    std::getline(ss, header);
    std::getline(ss, row_a);
    std::getline(ss, row_b);
    const auto h = split(header), ra = split(row_a), rb = split(row_b);
    auto cell = [&](const std::vector<std::string>& row, const std::string& column) {
        for (std::size_t i = 0; i < h.size(); ++i)
            if (h[i] == column) return row[i];
        FAIL("no column " << column);
        return std::string();
    };
    // A: two successful trials with f - f* = 1 and 3; one failed.
    REQUIRE(cell(ra, "runs") == "2");
    REQUIRE(cell(ra, "failed") == "1");
    REQUIRE(std::stod(cell(ra, "mean")) == Approx(2.0));
    REQUIRE(std::stod(cell(ra, "std")) == Approx(std::sqrt(2.0)));
    REQUIRE(std::stod(cell(ra, "Rs_mean")) == Approx(2.0));
    REQUIRE(std::stod(cell(ra, "Rs_err_pct")) == Approx(0.0).margin(1e-12));
    REQUIRE(std::stod(cell(ra, "Rs_std")) == Approx(std::sqrt(2.0)));
    // B: f - f* = 0.5, 0.25, 0: all below A's 1 and 3, so U = 0 and A12(B vs A) = 1; exact p = 2/C(5,2) = 0.2.
    REQUIRE(std::stod(cell(rb, "median")) == Approx(0.25));
    REQUIRE(std::stod(cell(rb, "a12_vs_A")) == Approx(1.0));
    REQUIRE(std::stod(cell(rb, "p_vs_A")) == Approx(0.2));
    REQUIRE(cell(ra, "p_vs_A").empty());

    const auto md = markdown_report(info, records);
    REQUIRE_THAT(md, Catch::Contains("| A | 2 (1 failed) |"));
    REQUIRE_THAT(md, Catch::Contains("| truth | 2 | 0 |"));
}

TEST_CASE("a label with a bar or a line break keeps its Markdown table row whole", "[report_tables]") {
    ExperimentInfo info;
    info.name = "t";
    info.trials = 1;
    PluginVariant a, b;
    a.label = "A|x";
    b.label = "B\nsecond line";
    info.optimizers = {a, b};
    ProblemInfo p;
    p.label = "P";
    p.dimension = 1;
    p.parameter_names = {"x1"};
    info.problems = {p, p};
    info.problems[1].label = "Q";
    info.baseline = a.label;
    info.references = {a.label};
    const Vector x = Vector::Zero(1);
    std::vector<TrialRecord> records{trial("A|x", 0, 2.0, x), trial("B\nsecond line", 0, 1.0, x)};
    for (auto r : std::vector<TrialRecord>(records)) {
        r.problem = "Q";
        records.push_back(r);
    }
    const auto md = markdown_report(info, records);
    // Each table line has as many unescaped bars as the header line above it.
    auto bars = [](const std::string& line) {
        std::size_t n = 0;
        for (std::size_t i = 0; i < line.size(); ++i) n += line[i] == '|' && (i == 0 || line[i - 1] != '\\');
        return n;
    };
    std::stringstream lines(md);
    std::string line;
    std::size_t header = 0, rows = 0;
    while (std::getline(lines, line)) {
        if (line.empty() || line[0] != '|') {
            header = 0;
            continue;
        }
        if (header == 0) header = bars(line);
        else ++rows;
        CHECK(bars(line) == header);
    }
    CHECK(rows >= 3 * 3);  // two problems' tables and the Friedman ranks, each a rule and two rows
    CHECK(md.find("| A\\|x |") != std::string::npos);
    CHECK(md.find("| B second line |") != std::string::npos);
    CHECK(md.find("p vs A\\|x") != std::string::npos);
}

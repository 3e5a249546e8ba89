// `mhbench evaluate PROBLEM [--dimension D] [--instance I] --points FILE|-`: the objective at given
// points, one value per line with 17 significant digits, so that any registered problem can be
// checked against another implementation (the organisers' CEC code, COCO) from the shell.
#include <charconv>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "framework/cli/commands.hpp"
#include "framework/cli/option_ranges.hpp"
#include "framework/cli/problem_option.hpp"
#include "framework/input_error.hpp"
#include "framework/registry.hpp"

namespace mhb::cli {
namespace {

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ','; }

// The numbers of one line: separated by spaces, tabs or commas; two commas with nothing between
// them leave a field empty, which is refused rather than skipped.
std::vector<double> parse_point(std::string line, const std::string& source, long line_number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::vector<double> numbers;
    bool field_open = true;  // a field is expected: at the start and after a comma
    std::size_t i = 0;
    while (i < line.size()) {
        if (line[i] == ' ' || line[i] == '\t') {
            ++i;
            continue;
        }
        if (line[i] == ',') {
            if (field_open)
                throw InputError(source, line_number, fmt::format("field {}", numbers.size() + 1), "empty (two separators in a row)");
            field_open = true;
            ++i;
            continue;
        }
        std::size_t end = i;
        while (end < line.size() && !is_separator(line[end])) ++end;
        const std::string token = line.substr(i, end - i);
        const char* first = token.data();
        if (*first == '+') ++first;  // from_chars takes no plus sign
        double value = 0.0;
        const auto [stop, ec] = std::from_chars(first, token.data() + token.size(), value);
        const std::string field = fmt::format("field {}", numbers.size() + 1);
        if (ec != std::errc() || stop != token.data() + token.size())
            throw InputError(source, line_number, field, fmt::format("'{}' is not a number", token));
        if (!std::isfinite(value)) throw InputError(source, line_number, field, fmt::format("'{}' is not finite", token));
        numbers.push_back(value);
        field_open = false;
        i = end;
    }
    if (field_open && !numbers.empty())
        throw InputError(source, line_number, fmt::format("field {}", numbers.size() + 1), "empty (the line ends with a comma)");
    return numbers;
}

}  // namespace

std::unique_ptr<Problem> problem_from_command_line(const std::string& name, std::optional<std::int64_t> dimension,
                                                   std::optional<std::int64_t> instance) {
    const auto& entry = ProblemRegistry::instance().at(name, "problem");
    auto declares = [&](const std::string& parameter) {
        for (const auto& p : entry.parameters)
            if (p.name == parameter) return true;
        return false;
    };
    std::map<std::string, ParameterValue> values;
    if (dimension && declares("dimension")) values["dimension"] = *dimension;
    if (instance) {
        if (!declares("instance"))
            throw InputError("command line", 0, "--instance", fmt::format("the problem {} has no instances", entry.name));
        values["instance"] = *instance;
    }
    std::unique_ptr<Problem> problem;
    try {
        problem = make_problem(entry.name, values);
    } catch (const ParameterError& e) {
        throw InputError("command line", 0, "--" + e.field(), e.message());
    }
    if (dimension && problem->dimension() != *dimension)
        throw InputError("command line", 0, "--dimension",
                         fmt::format("the problem {} has a fixed dimension of {} (got {})", entry.name, problem->dimension(),
                                     *dimension));
    return problem;
}

namespace {

int evaluate_points(const std::string& name, std::optional<std::int64_t> dimension, std::optional<std::int64_t> instance,
                    const std::string& points) {
    const auto problem = problem_from_command_line(name, dimension, instance);
    const int d = problem->dimension();
    std::ifstream file;
    if (points != "-") {
        file.open(points);
        if (!file) throw InputError(points, 0, "", "cannot open the points file");
    }
    std::istream& in = points == "-" ? std::cin : file;
    const std::string source = points == "-" ? "standard input" : points;

    std::vector<double> values;
    long line_number = 0, first_outside = 0, outside = 0;
    for (std::string line; std::getline(in, line);) {
        ++line_number;
        const auto point = parse_point(line, source, line_number);
        if (static_cast<int>(point.size()) != d)
            throw InputError(source, line_number, "",
                             fmt::format("{} number(s); {} with dimension {} needs {} per line", point.size(), name, d, d));
        for (int i = 0; i < d; ++i)
            if (point[static_cast<std::size_t>(i)] < problem->bounds().lower[i] ||
                point[static_cast<std::size_t>(i)] > problem->bounds().upper[i]) {
                if (outside++ == 0) first_outside = line_number;
                break;
            }
        values.insert(values.end(), point.begin(), point.end());
    }
    if (line_number == 0) throw InputError(source, 0, "", "no points (expected one point per line)");
    if (outside > 0)
        std::fprintf(stderr, "note: %s: %ld point(s) outside the box of %s, the first on line %ld; evaluated anyway\n",
                     source.c_str(), outside, name.c_str(), first_outside);

    const Eigen::Map<const Matrix> x(values.data(), d, line_number);
    Vector f(line_number);
    problem->evaluate(x, f);  // one population, so that the problem's batch path is what is checked
    std::string out;
    for (Eigen::Index j = 0; j < f.size(); ++j) out += fmt::format("{:.17g}\n", f[j]);
    std::fputs(out.c_str(), stdout);
    return exit_ok;
}

const bool registered = register_command("evaluate", [](CLI::App& app) {
    auto* cmd = app.add_subcommand("evaluate", "Evaluate a problem at given points: one value per line, 17 significant digits");
    struct Args {
        std::string problem, points;
        std::optional<std::int64_t> dimension, instance;
    };
    auto a = std::make_shared<Args>();
    cmd->add_option("PROBLEM", a->problem, "a registered problem (mhbench list problems)")->required();
    cmd->add_option("--dimension", a->dimension, "number of variables (default: the problem's)")
        ->check(whole_number_in<std::int64_t>(1, 1'000'000));
    cmd->add_option("--instance", a->instance, "instance of a problem that has them (BBOB)")
        ->check(whole_number_in<std::int64_t>(1, 1'000'000'000));
    cmd->add_option("--points", a->points,
                    "file with one point per line, numbers separated by spaces, tabs or commas; - for standard input")
        ->required();
    return std::function<int()>([a] { return evaluate_points(a->problem, a->dimension, a->instance, a->points); });
});

}  // namespace
}  // namespace mhb::cli

#include "problems/cec/cec_data.hpp"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "framework/input_error.hpp"
#include "framework/shared_problem_data.hpp"

namespace mhb::cec {
namespace {

std::atomic<std::size_t> files_read{0};

// One number of a data file and the line it stands on, for messages.
struct Number {
    double value;
    long line;
};

// Every line's numbers. The files are whitespace-separated (CRLF line ends); strtod reads each
// token the way the organisers' fscanf("%lf") does, so the values are theirs to the last bit.
std::vector<std::vector<Number>> read_numbers(const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file.string(), 0, "", "cannot open the CEC data file");
    ++files_read;
    std::vector<std::vector<Number>> lines;
    std::string text, token;
    long line = 0;
    while (std::getline(in, text)) {
        ++line;
        std::istringstream words(text);
        auto& numbers = lines.emplace_back();
        while (words >> token) {
            char* end = nullptr;
            const double value = std::strtod(token.c_str(), &end);
            if (end != token.c_str() + token.size())
                throw InputError(file.string(), line, "", fmt::format("'{}' is not a number", token));
            numbers.push_back({value, line});
        }
    }
    return lines;
}

std::vector<Number> in_sequence(const std::vector<std::vector<Number>>& lines) {
    std::vector<Number> all;
    for (const auto& l : lines) all.insert(all.end(), l.begin(), l.end());
    return all;
}

std::vector<Vector> read_shifts(const std::filesystem::path& file, int d, int components) {
    const auto lines = read_numbers(file);
    std::vector<Vector> shifts;
    for (int k = 0; k < components; ++k) {
        const auto line = static_cast<std::size_t>(k);
        if (line >= lines.size() || lines[line].size() < static_cast<std::size_t>(d))
            throw InputError(file.string(), k + 1, fmt::format("shift vector {}", k + 1),
                             fmt::format("expected at least {} numbers on this line", d));
        Vector o(d);
        for (int i = 0; i < d; ++i) o[i] = lines[line][static_cast<std::size_t>(i)].value;
        shifts.push_back(std::move(o));
    }
    return shifts;
}

// M_k is the k-th block of D*D numbers, row after row (the C code's Mr[i*D + j] is row i, column j).
std::vector<Matrix> read_rotations(const std::filesystem::path& file, int d, int components) {
    const auto numbers = in_sequence(read_numbers(file));
    const auto block = static_cast<std::size_t>(d) * static_cast<std::size_t>(d);
    if (numbers.size() < block * static_cast<std::size_t>(components))
        throw InputError(file.string(), numbers.empty() ? 0 : numbers.back().line, "",
                         fmt::format("holds {} numbers; {} rotation(s) of {}x{} need {}", numbers.size(), components, d,
                                     d, block * static_cast<std::size_t>(components)));
    std::vector<Matrix> rotations;
    for (int k = 0; k < components; ++k) {
        Matrix m(d, d);
        for (int i = 0; i < d; ++i)
            for (int j = 0; j < d; ++j)
                m(i, j) = numbers[static_cast<std::size_t>(k) * block + static_cast<std::size_t>(i * d + j)].value;
        rotations.push_back(std::move(m));
    }
    return rotations;
}

// The files hold one-based permutations of 1..D, D after D.
std::vector<std::vector<int>> read_permutations(const std::filesystem::path& file, int d, int components) {
    const auto numbers = in_sequence(read_numbers(file));
    if (numbers.size() < static_cast<std::size_t>(d) * static_cast<std::size_t>(components))
        throw InputError(file.string(), numbers.empty() ? 0 : numbers.back().line, "",
                         fmt::format("holds {} numbers; {} permutation(s) of {} need {}", numbers.size(), components,
                                     d, d * components));
    std::vector<std::vector<int>> permutations;
    for (int k = 0; k < components; ++k) {
        std::vector<int> p(static_cast<std::size_t>(d));
        std::vector<bool> seen(static_cast<std::size_t>(d), false);
        for (int i = 0; i < d; ++i) {
            const Number n = numbers[static_cast<std::size_t>(k * d + i)];
            const int one_based = static_cast<int>(n.value);
            if (one_based != n.value || one_based < 1 || one_based > d || seen[static_cast<std::size_t>(one_based - 1)])
                throw InputError(file.string(), n.line, fmt::format("permutation {}", k + 1),
                                 fmt::format("{} is not a new index in 1..{}", n.value, d));
            seen[static_cast<std::size_t>(one_based - 1)] = true;
            p[static_cast<std::size_t>(i)] = one_based - 1;
        }
        permutations.push_back(std::move(p));
    }
    return permutations;
}

FunctionData read_function_data(const DataRequest& r, const std::filesystem::path& folder) {
    const auto suite = folder / r.suite;
    FunctionData data;
    data.shifts = read_shifts(suite / fmt::format("shift_data_{}.txt", r.function), r.dimension, r.components);
    data.rotations =
        read_rotations(suite / fmt::format("M_{}_D{}.txt", r.function, r.dimension), r.dimension, r.components);
    if (r.shuffled)
        data.permutations = read_permutations(suite / fmt::format("shuffle_data_{}_D{}.txt", r.function, r.dimension),
                                              r.dimension, r.components);
    return data;
}

}  // namespace

std::filesystem::path vendored_data_directory() {
    const std::filesystem::path source_tree = MHBENCH_CEC_DATA_DIR;
    if (std::filesystem::is_directory(source_tree)) return source_tree;
    std::error_code ec;
    const auto program = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) {
        const auto installed = program.parent_path().parent_path() / "share" / "mhbench" / "cec";
        if (std::filesystem::is_directory(installed)) return installed;
    }
    return source_tree;
}

std::shared_ptr<const FunctionData> function_data(const DataRequest& request) {
    // The suites' data are constants, not inputs of an experiment: one store for the whole process
    // keeps them across experiments and `evaluate` calls, where a per-experiment store would not.
    static SharedProblemData store;
    const auto folder = request.folder.empty() ? vendored_data_directory() : request.folder;
    const std::string key = fmt::format("{}|{}|{}|{}|{}|{}", folder.string(), request.suite, request.function,
                                        request.dimension, request.components, request.shuffled);
    return store.get<FunctionData>(key, [&] { return read_function_data(request, folder); });
}

std::size_t data_files_read() { return files_read.load(); }

}  // namespace mhb::cec

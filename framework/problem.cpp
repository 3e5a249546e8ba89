#include "framework/problem.hpp"

#include <stdexcept>

namespace mhb {

void Problem::set_domain(Vector lower, Vector upper, std::vector<std::string> names) {
    if (lower.size() != upper.size() || lower.size() == 0)
        throw std::invalid_argument("problem bounds must be two non-empty vectors of equal size");
    for (Eigen::Index j = 0; j < lower.size(); ++j)
        if (!(lower[j] <= upper[j]))
            throw std::invalid_argument("problem bounds: lower > upper in coordinate " + std::to_string(j + 1));
    named_parameters_ = !names.empty();
    if (names.empty())
        for (Eigen::Index j = 0; j < lower.size(); ++j) names.push_back("x" + std::to_string(j + 1));
    if (static_cast<Eigen::Index>(names.size()) != lower.size())
        throw std::invalid_argument("problem: one name per coordinate is needed");
    bounds_ = Bounds{std::move(lower), std::move(upper)};
    parameter_names_ = std::move(names);
}

void Problem::set_domain(int dimension, double lower, double upper) {
    set_domain(Vector::Constant(dimension, lower), Vector::Constant(dimension, upper));
}

}  // namespace mhb

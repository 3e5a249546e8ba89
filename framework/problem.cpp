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

void Problem::override_bounds(const Vector& lower, const Vector& upper) {
    if (lower.size() != dimension() || upper.size() != dimension())
        throw std::invalid_argument("bounds need " + std::to_string(dimension()) + " values (one per parameter) or one for all");
    for (Eigen::Index j = 0; j < lower.size(); ++j)
        if (!(lower[j] <= upper[j]))
            throw std::invalid_argument("lower > upper for " + parameter_names_[static_cast<std::size_t>(j)] + " (" +
                                        std::to_string(lower[j]) + " > " + std::to_string(upper[j]) + ")");
    bounds_ = Bounds{lower, upper};
    bounds_changed();
}

void Problem::set_domain(int dimension, double lower, double upper) {
    set_domain(Vector::Constant(dimension, lower), Vector::Constant(dimension, upper));
}

}  // namespace mhb

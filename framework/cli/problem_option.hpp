#pragma once
// A registered problem made from the command line's options, as `evaluate` and `complexity` take them.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "framework/problem.hpp"

namespace mhb::cli {

// The problem `name` at `dimension` (for problems that declare one; a problem of fixed dimension
// must have that one) and `instance` (for problems that declare instances). InputError naming the
// option (--dimension, --instance) otherwise; UnknownPlugin for a name not registered.
std::unique_ptr<Problem> problem_from_command_line(const std::string& name, std::optional<std::int64_t> dimension,
                                                   std::optional<std::int64_t> instance);

}  // namespace mhb::cli

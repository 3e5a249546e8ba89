// An optimizer registered under the name of a built-in one ("gwo"): the program must refuse the library.
#include "idle_optimizer.hpp"

namespace {
const bool registered = fixture::register_idle_optimizer("gwo", "a plugin's optimizer that takes a built-in's name");
}  // namespace

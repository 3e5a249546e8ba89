// Needs a function that nothing defines, as a plugin linked against a library the program lacks would.
extern "C" int mhbench_fixture_function_nobody_defines();

namespace {
const int value = mhbench_fixture_function_nobody_defines();
}  // namespace

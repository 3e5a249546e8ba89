// A shared library built without mhbench::plugin: it has no interface version.
extern "C" int mhbench_fixture_answer() { return 42; }

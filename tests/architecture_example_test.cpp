// The optimizer example of docs/architecture.md is a real plugin (docs/examples/gaussian_search.cpp,
// compiled into this binary): the page shows exactly that file, and it works as a plugin should.
#include <catch2/catch.hpp>

#include <fstream>

#include "framework/registry.hpp"
#include "framework/trial.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

TEST_CASE("docs/architecture.md shows the example optimizer file verbatim", "[architecture_example]") {
    auto read = [](const std::string& path) {
        std::ifstream in(std::string(MHBENCH_SOURCE_DIR) + "/" + path);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    const std::string source = read("docs/examples/gaussian_search.cpp");
    REQUIRE(source.size() > 1000);
    REQUIRE(read("docs/architecture.md").find("```cpp\n" + source + "```\n") != std::string::npos);
}

TEST_CASE("the example optimizer keeps its budget and converges on a shifted sphere", "[architecture_example]") {
    testing::ShiftedSphere sphere(5, -5, 5, 1.7);
    auto opt = make_optimizer("example_gaussian_search");
    const auto r = run_trial(*opt, sphere, {Budget{0, 20000}, 3, false});
    REQUIRE(r.ok);
    REQUIRE(r.evaluations == 20000);
    // Greedy steps shrinking to 0.1 % of the box (0.01 here) end each individual within a few steps
    // of the optimum: f of order 5 * 0.01^2; 1e-2 leaves a wide margin.
    REQUIRE(r.best_fitness < 1e-2);
}

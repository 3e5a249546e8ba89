// SharedProblemData: one build per key however many trials ask at once, and a failed build stores nothing.
#include <catch2/catch.hpp>

#include <atomic>
#include <stdexcept>

#include <tbb/parallel_for.h>

#include "framework/shared_problem_data.hpp"

using mhb::SharedProblemData;

TEST_CASE("concurrent requests for one key build it once and all see the same value", "[shared_problem_data]") {
    SharedProblemData shared;
    std::atomic<int> calls{0};
    std::vector<const std::vector<double>*> seen(64);
    tbb::parallel_for(0, 64, [&](int k) {
        const auto value = shared.get<std::vector<double>>("data.csv", [&] {
            ++calls;
            return std::vector<double>(1000, 1.5);
        });
        seen[static_cast<std::size_t>(k)] = value.get();
    });
    CHECK(calls == 1);
    CHECK(shared.builds() == 1);
    for (const auto* p : seen) CHECK(p == seen.front());
    // Another key is another value.
    const auto other = shared.get<std::vector<double>>("other.csv", [] { return std::vector<double>(2, 0.0); });
    CHECK(other->size() == 2);
    CHECK(shared.builds() == 2);
}

TEST_CASE("a build that throws stores nothing, and the next request builds again", "[shared_problem_data]") {
    SharedProblemData shared;
    CHECK_THROWS_AS(shared.get<int>("k", []() -> int { throw std::runtime_error("unreadable"); }), std::runtime_error);
    CHECK(shared.builds() == 0);
    CHECK(*shared.get<int>("k", [] { return 7; }) == 7);
    CHECK(shared.builds() == 1);
}

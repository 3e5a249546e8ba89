#include <catch2/catch.hpp>

#include "framework/registry.hpp"
#include "tests/sphere_fixture.hpp"

using namespace mhb;

TEST_CASE("plugins found case-insensitively, and unknown names list what exists", "[registry]") {
    REQUIRE(OptimizerRegistry::instance().find("random_search") != nullptr);
    REQUIRE(OptimizerRegistry::instance().find("RANDOM_SEARCH") != nullptr);
    try {
        make_optimizer("no_such_optimizer");
        FAIL("accepted an unknown optimizer");
    } catch (const UnknownPlugin& e) {
        REQUIRE_THAT(e.what(), Catch::Contains("random_search"));
    }
    try {
        make_optimizer("cmaez");
        FAIL("accepted a misspelt optimizer");
    } catch (const UnknownPlugin& e) {
        // The closest name, then every name on a line of its own.
        REQUIRE_THAT(e.what(), Catch::StartsWith("unknown optimizer 'cmaez'; did you mean 'cmaes'? Registered optimizers:\n"));
        REQUIRE_THAT(e.what(), Catch::Contains("\n  random_search\n") || Catch::EndsWith("\n  random_search"));
    }
    REQUIRE(OptimizerRegistry::instance().conflicts().empty());
    REQUIRE(ProblemRegistry::instance().conflicts().empty());
}

TEST_CASE("a second registration under a taken name is reported, not silently replaced", "[registry]") {
    Registry<int> local;
    REQUIRE(local.add({"alpha", "first", {}, 1}));
    REQUIRE_FALSE(local.add({"Alpha", "second", {}, 2}));
    REQUIRE(local.find("alpha")->create == 1);
    REQUIRE(local.conflicts() == std::vector<RegistrationClash>{{"Alpha", "built-in", "built-in"}});
}

TEST_CASE("a clash names where each registration came from", "[registry]") {
    Registry<int> local;
    REQUIRE(local.add({"gwo", "the program's", {}, 1}));
    set_registration_origin("/opt/plugins/libwolves.so");
    const bool added = local.add({"GWO", "a plugin's", {}, 2});
    set_registration_origin("built-in");
    REQUIRE_FALSE(added);
    REQUIRE(local.origin("gwo") == "built-in");
    REQUIRE(clash_message("optimizer", local.conflicts().at(0)) ==
            "the optimizer 'GWO' of /opt/plugins/libwolves.so clashes with the built-in optimizer 'GWO'; rename one of them");
}

TEST_CASE("registry lists names in natural order", "[registry]") {
    Registry<int> local;
    for (const char* n : {"F10", "F2", "F1", "bbob_f3"}) local.add({n, "", {}, 0});
    std::vector<std::string> names;
    for (const auto* e : local.entries()) names.push_back(e->name);
    REQUIRE(names == std::vector<std::string>{"bbob_f3", "F1", "F2", "F10"});
}

TEST_CASE("the closest name is suggested only when it is a likely typo", "[registry]") {
    const std::vector<std::string> known{"cmaes", "de", "gwo", "isoa", "pso", "random_search", "soa"};
    CHECK(closest_name("cmaez", known) == "cmaes");
    CHECK(closest_name("CMAES", known) == "cmaes");
    CHECK(closest_name("random_serach", known) == "random_search");
    CHECK(closest_name("gw", known) == "gwo");
    CHECK(closest_name("simulated_annealing", known).empty());
    CHECK(unknown_name_message("command", "fitt", {"diagnose", "fit", "list"}) ==
          "unknown command 'fitt'; did you mean 'fit'? Registered commands:\n  diagnose\n  fit\n  list");
}

#include <catch2/catch.hpp>

#include "framework/input_error.hpp"
#include "framework/parameters.hpp"

using namespace mhb;

namespace {
std::vector<ParameterSpec> specs() {
    return {ParameterSpec::integer("population", 30, 4, 10000, "wolves"),
            ParameterSpec::real("rate", 0.3, 0.0, 1.0, "jumping rate"),
            ParameterSpec::boolean("greedy", false, "greedy selection"),
            ParameterSpec::choice("variant", "original", {"original", "greedy_top3"}, "update rule")};
}
}  // namespace

TEST_CASE("defaults apply and values override them", "[parameters]") {
    ParameterSet p(specs(), {{"population", std::int64_t{50}}, {"rate", std::int64_t{1}}});
    REQUIRE(p.integer("population") == 50);
    REQUIRE(p.real("rate") == 1.0);  // an integer is accepted for a real parameter
    REQUIRE(p.boolean("greedy") == false);
    REQUIRE(p.text("variant") == "original");
    REQUIRE(p.non_default_text() == "population=50,rate=1");
}

TEST_CASE("bad parameter values are refused with the parameter's name", "[parameters]") {
    auto refuses = [](std::map<std::string, ParameterValue> given, const std::string& field, const std::string& part) {
        try {
            ParameterSet p(specs(), given);
            FAIL("accepted");
        } catch (const ParameterError& e) {
            CHECK(e.field() == field);
            CHECK_THAT(e.message(), Catch::Contains(part));
        }
    };
    refuses({{"population", std::int64_t{2}}}, "population", "[4, 10000]");
    refuses({{"population", 3.5}}, "population", "integer");
    refuses({{"rate", 1.5}}, "rate", "[0, 1]");
    refuses({{"rate", std::string("x")}}, "rate", "number");
    refuses({{"greedy", std::int64_t{1}}}, "greedy", "true or false");
    refuses({{"variant", std::string("other")}}, "variant", "{original, greedy_top3}");
    refuses({{"populaton", std::int64_t{30}}}, "populaton", "known: population, rate, greedy, variant");
}

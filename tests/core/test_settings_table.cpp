// The typed settings description (core/settings_table.hpp): reading refuses what does not fit a
// field by its name, and writing and reading give back the same struct; that the docs list every
// key // with what the code accepts (tests/apps/test_cmd_options.cpp).
#include <catch2/catch.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/settings_table.hpp"

using namespace confpack;
using core::Range;
using nlohmann::json;

namespace {

enum class Colour { Red, Blue };

struct Example {
  double length = 1.0;
  double limit = std::numeric_limits<double>::infinity();
  int count = 3;
  long big = 10;
  bool on = false;
  Colour colour = Colour::Red;
  std::string name = "unnamed";
};

core::SettingsTable<Example> exampleTable() {
  core::SettingsTable<Example> t("example");
  t.number("length", &Example::length, Range::leftOpen(0.0, 2.0), "d", "a length")
      .numberOrNone("limit", &Example::limit, Range::positive(), "d", "a bound or none")
      .integer("count", &Example::count, Range::closed(1.0, 5.0), "-", "a count")
      .integer("big", &Example::big, Range::atLeast(0.0), "-", "a large count")
      .flag("on", &Example::on, "a switch")
      .choice("colour", &Example::colour, {{"red", Colour::Red}, {"blue", Colour::Blue}}, "a choice")
      .text("name", &Example::name, "a name")
      .rule([](const Example& e) {
        if (e.count > e.big) throw std::invalid_argument("example.count: must be at most big");
      });
  return t;  // returned by value: the readers must not refer to the table they were made in
}

}  // namespace

TEST_CASE("settings table: ranges say what they accept") {
  CHECK(Range::leftOpen(0.0, 2.0).text() == "in (0, 2]");
  CHECK(Range::closed(0.5, 1.0).text() == "in [0.5, 1]");
  CHECK(Range::positive().text() == "> 0");
  CHECK(Range::atLeast(1.0).text() == ">= 1");
  CHECK(Range::atMost(0.0).text() == "<= 0");
  CHECK(Range::leftOpen(0.0, 2.0).contains(2.0));
  CHECK_FALSE(Range::leftOpen(0.0, 2.0).contains(0.0));
  CHECK_FALSE(Range::any().contains(std::numeric_limits<double>::infinity()));
  CHECK_FALSE(Range::any().contains(std::numeric_limits<double>::quiet_NaN()));
}

TEST_CASE("settings table: reads the keys given, refuses the rest by name") {
  const auto t = exampleTable();
  Example e;
  t.read({{"length", 0.5},
          {"limit", nullptr},
          {"count", 4},
          {"on", true},
          {"colour", "blue"},
          {"big", 1LL << 40},
          {"name", "Scott"}},
         e);
  CHECK(e.length == 0.5);
  CHECK(e.limit == std::numeric_limits<double>::infinity());
  CHECK(e.count == 4);
  CHECK(e.big == 1LL << 40);
  CHECK(e.on);
  CHECK(e.colour == Colour::Blue);
  CHECK(e.name == "Scott");

  auto refused = [&](const json& j, const std::string& message) {
    Example x;
    INFO(j.dump());
    CHECK_THROWS_WITH(t.read(j, x), message);
  };
  refused({{"lenght", 1.0}}, "example.lenght: unknown key (known: length, limit, count, big, on, colour, name)");
  refused({{std::string(1000, 'k'), 1.0}},
          "example." + std::string(40, 'k') + "...: unknown key (known: length, limit, count, big, on, colour, name)");
  refused({{"length", 0.0}}, "example.length: must be in (0, 2] (got 0)");
  refused({{"length", "long"}}, "example.length: must be a number (got \"long\")");
  refused({{"limit", -1.0}}, "example.limit: must be > 0 (got -1)");
  refused({{"count", 2.5}}, "example.count: must be an integer (got 2.5)");
  refused({{"count", 6}}, "example.count: must be in [1, 5] (got 6)");
  // Beyond what an int holds: refused, not wrapped to a small number.
  refused({{"count", 1LL << 40}}, "example.count: must be in [1, 5] (got 1099511627776)");
  refused({{"on", 1}}, "example.on: must be true or false (got 1)");
  refused({{"colour", "green"}}, "example.colour: must be \"red\" or \"blue\" (got \"green\")");
  refused({{"name", ""}}, "example.name: must be a non-empty string (got \"\")");
  refused({{"name", 3}}, "example.name: must be a non-empty string (got 3)");
  refused({{"count", 5}, {"big", 2}}, "example.count: must be at most big");
  refused(json::array(), "example: must be a JSON object (got array)");
}

TEST_CASE("settings table: what it writes it reads back, none for infinity") {
  const auto t = exampleTable();
  Example e;
  e.length = 1.5;
  e.colour = Colour::Blue;
  e.name = "a reference";
  const json j = t.write(e);
  CHECK(j["limit"].is_null());
  CHECK(j["colour"] == "blue");
  Example back;
  back.length = 0.1;
  t.read(j, back);
  CHECK(t.write(back) == j);
}

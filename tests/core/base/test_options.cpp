// The option table (peelcd/core/options.h): every row's default is valid and reads back, every
// bounded row refuses what lies outside its range with a message that names the key, integers
// must be integral, choices parse their own words and refuse others, validate_options() applies
// the table and the stage's largest view.
#include "peelcd/core/image/detector.h"
#include "peelcd/core/options.h"

#include <catch2/catch.hpp>

#include <cmath>
#include <set>
#include <sstream>

using namespace peelcd;

TEST_CASE("options: every key once, every default valid and set back unchanged", "[options]") {
  std::set<std::string> keys;
  const DetectOptions defaults;
  for (const OptionSpec& spec : option_table()) {
    INFO(spec.key);
    CHECK(keys.insert(spec.key).second);
    CHECK(find_option(spec.key) == &spec);
    const OptionValue v = spec.get(defaults);
    CHECK(check_option(spec, v).empty());
    DetectOptions o;
    set_option(o, spec, v, "test");
    CHECK(spec.get(o) == v);
  }
  CHECK(find_option("no such option") == nullptr);
  CHECK_NOTHROW(validate_options(defaults, 16384));
}

TEST_CASE("options: a value outside a row's range is refused, naming the key and the range", "[options][nonfinite]") {
  for (const OptionSpec& spec : option_table()) {
    if (spec.kind != OptionSpec::Kind::integer && spec.kind != OptionSpec::Kind::number) continue;
    INFO(spec.key);
    for (const double bad : {spec.min - 1.0, spec.max * 2.0 + 1.0, std::nan(""), HUGE_VAL}) {
      if (std::isfinite(bad) && bad >= spec.min && bad <= spec.max) continue;  // an unbounded side
      CHECK_FALSE(check_option(spec, OptionValue(bad)).empty());
      DetectOptions o;
      try {
        set_option(o, spec, OptionValue(bad), "here");
        FAIL("accepted " << bad);
      } catch (const std::invalid_argument& e) {
        CHECK(std::string(e.what()).find("here") != std::string::npos);
      }
    }
    if (spec.kind == OptionSpec::Kind::integer && spec.max - spec.min >= 1.0)
      CHECK_FALSE(check_option(spec, OptionValue(spec.min + 0.5)).empty());  // not integral
    CHECK_FALSE(check_option(spec, OptionValue(std::string("3"))).empty());  // the wrong kind
  }
}

TEST_CASE("options: choices parse their own words and refuse others", "[options]") {
  for (const OptionSpec& spec : option_table()) {
    if (spec.kind != OptionSpec::Kind::choice) continue;
    INFO(spec.key);
    std::stringstream words(spec.choices);
    std::string word;
    while (std::getline(words, word, ',')) {
      std::string problem;
      const OptionValue v = parse_option(spec, word, problem);
      CHECK(problem.empty());
      CHECK(check_option(spec, v).empty());
    }
    std::string problem;
    parse_option(spec, "no-such-word", problem);
    CHECK(problem.find("no-such-word") != std::string::npos);
  }
}

TEST_CASE("options: validate_options() refuses a view larger than the stage's, naming it", "[options]") {
  DetectOptions o;
  o.resolution = 1024;
  CHECK_NOTHROW(validate_options(o, 1024));
  CHECK_THROWS_WITH(validate_options(o, 512), Catch::Contains("resolution 1024"));
  o.resolution = 0;
  o.budget = 4096;
  CHECK_THROWS_WITH(validate_options(o, 2048), Catch::Contains("budget 4096"));
  o.budget = 512;
  o.views = 4;
  CHECK_THROWS_WITH(validate_options(o, 2048), Catch::Contains("views"));
}

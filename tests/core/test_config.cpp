// Config parsing: JSON objects and key=value items. Every malformed input is a corrlap InputError
// naming the origin, the key and the position; no nlohmann exception escapes (reliability probe:
// {"tolerance": 1e999} used to escape as out_of_range, reported as an internal error).
#include <doctest/doctest.h>

#include <corrlap/core/config.hpp>
#include <corrlap/core/error.hpp>
#include <stdexcept>
#include <string>

#include "test_support.hpp"

using namespace corrlap;

namespace {
// The message of the InputError thrown by f, or "" (and a failed check) when none is thrown.
template <class F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    FAIL("not an InputError: " << e.what());
  }
  FAIL("no exception");
  return "";
}
}  // namespace

TEST_CASE("config JSON: values, types and the last duplicate win") {
  const Config c = Config::from_json_string(R"({"solver": "cholmod", "t": 0.5, "n": 12, "big": 18446744073709551615,
                                               "x": true, "t": 0.25})");
  CHECK(c.get_string("solver", "") == "cholmod");
  CHECK(c.get_double("t", 0) == 0.25);
  CHECK(c.get_int("n", 0) == 12);
  CHECK(c.get_double("big", 0) == 18446744073709551615.0);
  CHECK(c.get_bool("x", false));
  CHECK(c.keys().size() == 5);
  CHECK(Config::from_json_string("{}").empty());
  CHECK(Config::from_json_string(c.to_json()).get_double("t", 0) == 0.25);
}

TEST_CASE("config JSON: overflow, syntax and nesting errors name the key and the position") {
  std::string m = input_error([] { Config::from_json_string("{\"a\": 1,\n \"tolerance\": 1e999}", "run.json"); });
  CHECK(m == "run.json: number '1e999' at line 2, column 15 (value of key 'tolerance') is out of the range of double");
  m = input_error([] { Config::from_json_string("{\"t\": -1e400}"); });
  CHECK(m.find("number '-1e400'") != std::string::npos);
  m = input_error([] { Config::from_json_string("{\"a\": 1,\n \"b\": }", "c.json"); });
  CAPTURE(m);
  CHECK(m.find("c.json: invalid JSON (value of key 'b'): ") == 0);
  CHECK(m.find("line 2, column 7") != std::string::npos);
  m = input_error([] { Config::from_json_string("{\"a\": [1, 2]}"); });
  CHECK(m == "config: value of key 'a' must be a string, a number or a boolean, not an array");
  m = input_error([] { Config::from_json_string("{\"a\": null}"); });
  CHECK(m.find("not null") != std::string::npos);
  m = input_error([] { Config::from_json_string("[1, 2]"); });
  CHECK(m.find("expected a JSON object") != std::string::npos);
  m = input_error([] { Config::from_json_string("3"); });
  CHECK(m.find("expected a JSON object") != std::string::npos);
  m = input_error([] { Config::from_json_string("{\"a\": 1} {\"b\": 2}"); });
  CHECK(m.find("config: invalid JSON: ") == 0);
  CHECK(m.find("line 1, column 10") != std::string::npos);
  // A deeply nested value is rejected at its first '[' (no DOM is built).
  m = input_error([] { Config::from_json_string("{\"a\": " + std::string(100000, '[')); });
  CHECK(m.find("value of key 'a'") != std::string::npos);
  // From a file: the message names the file.
  const std::string path = corrlap::test::tmp_path("overflow.json");
  corrlap::test::write_text(path, "{\"tolerance\": 1e999}");
  m = input_error([&] { Config::from_json_file(path); });
  CHECK(m.find("config file '" + path + "': number '1e999' at line 1, column 15 (value of key 'tolerance')") == 0);
}

TEST_CASE("config key=value items: numbers must be finite") {
  const Config c = Config::from_key_values({"a=1e3", "b=true", "c=cholmod", "d=nancy"});
  CHECK(c.get_double("a", 0) == 1000.0);
  CHECK(c.get_bool("b", false));
  CHECK(c.get_string("c", "") == "cholmod");
  CHECK(c.get_string("d", "") == "nancy");
  CHECK(input_error([] { Config::from_key_values({"tolerance=1e999"}); }) ==
        "config item 'tolerance=1e999': '1e999' is not a finite number");
  CHECK(input_error([] { Config::from_key_values({"t=nan"}); }).find("not a finite number") != std::string::npos);
  CHECK(input_error([] { Config::from_key_values({"=3"}); }).find("expected key=value") != std::string::npos);
}

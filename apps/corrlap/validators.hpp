#pragma once
// Option checks with messages a user can read: CLI11's PositiveNumber / NonNegativeNumber print
// their range bound, the largest double, as a 309-digit number.
#include <CLI/CLI.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace corrlap::cli {

namespace detail {
inline CLI::Validator number_check(const char* description, bool (*accept)(double)) {
  return CLI::Validator(
      [description, accept](std::string& text) -> std::string {
        double value = 0.0;
        std::size_t used = 0;
        try {
          value = std::stod(text, &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used != text.size() || used == 0) return "'" + text + "' is not a number";
        if (!std::isfinite(value) || !accept(value))
          return "must be " + std::string(description) + " (got " + text + ")";
        return {};
      },
      description);
}
}  // namespace detail

/// A finite number > 0.
inline CLI::Validator positive_number() {
  return detail::number_check("a positive number", [](double v) { return v > 0.0; });
}
/// A finite number >= 0.
inline CLI::Validator non_negative_number() {
  return detail::number_check("a number >= 0", [](double v) { return v >= 0.0; });
}

/// A finite number >= 0, or the word `word` (e.g. "auto").
inline CLI::Validator non_negative_number_or(const std::string& word) {
  const CLI::Validator number = non_negative_number();
  return CLI::Validator(
      [word, number](std::string& text) -> std::string {
        if (text == word) return {};
        std::string copy = text;
        const std::string error = number(copy);
        return error.empty() ? error : error + " or '" + word + "'";
      },
      "a number >= 0 or '" + word + "'");
}

/// "a,b,,c" -> {"a", "b", "c"}: the comma lists of --methods, --shapes, --functions.
inline std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) items.push_back(item);
  return items;
}

/// A default as a user would type it (4, 0.33), for help texts built from the library's constants.
inline std::string number_text(double value) {
  std::ostringstream os;
  os << value;
  return os.str();
}

}  // namespace corrlap::cli

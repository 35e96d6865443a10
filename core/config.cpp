#include "config.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "error.hpp"

namespace corrlap {

namespace {

// Line and column (1-based) of byte `offset` of text, for error messages.
std::string line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// Builds the flat key -> value map straight from the parser's SAX events: no DOM, a nested value is
// rejected at its first token, and the parser's own errors (syntax, number overflow such as 1e999,
// which nlohmann reports as out_of_range) become InputErrors naming the key and the position
// instead of escaping as nlohmann exceptions.
class FlatObjectSax {
 public:
  using json = nlohmann::json;
  FlatObjectSax(std::string_view text, std::string_view origin, std::map<std::string, Config::Value>& out)
      : text_(text), origin_(origin), out_(out) {}

  bool null() { return scalar_error("null"); }
  bool boolean(bool v) { return put(v); }
  bool number_integer(json::number_integer_t v) { return put(double(v)); }
  bool number_unsigned(json::number_unsigned_t v) { return put(double(v)); }
  bool number_float(json::number_float_t v, const json::string_t&) { return put(double(v)); }
  bool string(json::string_t& v) { return put(std::string(v)); }
  bool binary(json::binary_t&) { return scalar_error("binary data"); }
  bool start_object(std::size_t) {
    if (depth_++ == 0) return true;
    return scalar_error("an object");
  }
  bool key(json::string_t& k) {
    key_ = k;
    return true;
  }
  bool end_object() {
    if (--depth_ == 0) key_.clear();  // an error after the object is not about its last key
    return true;
  }
  bool start_array(std::size_t) { return scalar_error("an array"); }
  bool end_array() { return true; }
  bool parse_error(std::size_t position, const std::string& last_token, const nlohmann::detail::exception& ex) {
    const std::string of_key = key_.empty() ? std::string() : " (value of key '" + key_ + "')";
    if (ex.id == 406) {  // out_of_range.406: the number does not fit in a double. Its message has no
      // position; `position` counts the characters read, the token included: point at its start.
      const std::string at = line_column(text_, position >= last_token.size() ? position - last_token.size() : 0);
      throw InputError(std::string(origin_) + ": number '" + last_token.substr(0, 40) + "' at " + at + of_key +
                       " is out of the range of double");
    }
    // Syntax errors: nlohmann's message already names the line and column.
    throw InputError(std::string(origin_) + ": invalid JSON" + of_key + ": " + ex.what());
  }

 private:
  template <class T>
  bool put(T v) {
    if (depth_ == 0) throw InputError(std::string(origin_) + ": expected a JSON object {\"key\": value, ...}");
    out_[key_] = std::move(v);
    return true;
  }
  bool scalar_error(const char* what) {
    if (depth_ == 0) throw InputError(std::string(origin_) + ": expected a JSON object {\"key\": value, ...}");
    throw InputError(std::string(origin_) + ": value of key '" + key_ +
                     "' must be a string, a number or a boolean, not " + what);
  }

  std::string_view text_, origin_;
  std::map<std::string, Config::Value>& out_;
  std::string key_;
  int depth_ = 0;
};

}  // namespace

Config Config::from_json_string(std::string_view text, std::string_view origin) {
  Config c;
  FlatObjectSax sax(text, origin, c.values_);
  try {
    if (!nlohmann::json::sax_parse(text.begin(), text.end(), &sax))
      throw InputError(std::string(origin) + ": invalid JSON");
  } catch (const nlohmann::json::exception& e) {  // anything the handler did not see first
    throw InputError(std::string(origin) + ": invalid JSON: " + e.what());
  }
  return c;
}

Config Config::from_json_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IoError("config file '" + path + "': cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (ss.str().find_first_not_of(" \t\r\n") == std::string::npos)
    throw IoError("config file '" + path + "': empty file");
  return from_json_string(ss.str(), "config file '" + path + "'");
}

Config Config::from_key_values(const std::vector<std::string>& items) {
  Config c;
  for (const auto& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("config item '" + item + "': expected key=value");
    const std::string key = item.substr(0, eq), text = item.substr(eq + 1);
    if (text == "true" || text == "false") {
      c.values_[key] = (text == "true");
      continue;
    }
    char* end = nullptr;
    const double d = std::strtod(text.c_str(), &end);
    if (!text.empty() && end == text.c_str() + text.size()) {
      // strtod turns 1e999 into inf and accepts "nan": a config number must be finite.
      if (!std::isfinite(d)) throw InputError("config item '" + item + "': '" + text + "' is not a finite number");
      c.values_[key] = d;
    } else {
      c.values_[key] = text;
    }
  }
  return c;
}

void Config::merge(const Config& other) {
  for (const auto& [k, v] : other.values_) values_[k] = v;
}

std::vector<std::string> Config::keys() const {
  std::vector<std::string> k;
  for (const auto& [key, v] : values_) k.push_back(key);
  return k;
}

std::string Config::get_string(const std::string& key, const std::string& fallback) const {
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  if (const auto* s = std::get_if<std::string>(&it->second)) return *s;
  if (const auto* d = std::get_if<double>(&it->second)) {
    std::ostringstream os;
    os.precision(17);
    os << *d;
    return os.str();
  }
  return std::get<bool>(it->second) ? "true" : "false";
}

double Config::get_double(const std::string& key, double fallback) const {
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  if (const auto* d = std::get_if<double>(&it->second)) return *d;
  throw InputError("config key '" + key + "': expected a number, got '" + get_string(key, "") + "'");
}

int Config::get_int(const std::string& key, int fallback) const {
  if (!has(key)) return fallback;
  const double d = get_double(key, fallback);
  if (d != std::floor(d) || std::abs(d) > 2147483647.0)
    throw InputError("config key '" + key + "': expected an integer, got " + get_string(key, ""));
  return int(d);
}

bool Config::get_bool(const std::string& key, bool fallback) const {
  auto it = values_.find(key);
  if (it == values_.end()) return fallback;
  if (const auto* b = std::get_if<bool>(&it->second)) return *b;
  if (const auto* d = std::get_if<double>(&it->second)) {
    if (*d == 0.0 || *d == 1.0) return *d == 1.0;
  }
  throw InputError("config key '" + key + "': expected true or false, got '" + get_string(key, "") + "'");
}

void Config::check_keys(const std::vector<std::string>& allowed, std::string_view context) const {
  std::vector<std::string> unknown;
  for (const auto& [k, v] : values_)
    if (std::find(allowed.begin(), allowed.end(), k) == allowed.end()) unknown.push_back(k);
  if (unknown.empty()) return;
  std::ostringstream os;
  os << context << ": unknown config key" << (unknown.size() > 1 ? "s" : "");
  for (const auto& k : unknown) os << " '" << k << "'";
  os << "; valid keys:";
  for (const auto& k : allowed) os << " " << k;
  throw InputError(os.str());
}

void Config::check_parameters(const std::vector<ParameterInfo>& documented, std::string_view context) const {
  std::vector<std::string> names;
  names.reserve(documented.size());
  for (const auto& p : documented) names.push_back(p.name);
  check_keys(names, context);
}

std::string Config::to_json() const {
  nlohmann::json j = nlohmann::json::object();
  // The key is captured by copy: clang 14 rejects capturing a structured binding (C++20 allows it).
  for (const auto& [k, v] : values_) std::visit([&j, key = k](const auto& x) { j[key] = x; }, v);
  return j.dump();
}

}  // namespace corrlap

#include "config.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "error.hpp"

namespace corrlap {

Config Config::from_json_string(std::string_view text, std::string_view origin) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text.begin(), text.end());
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(std::string(origin) + ": invalid JSON: " + e.what());
  }
  if (!j.is_object()) throw InputError(std::string(origin) + ": expected a JSON object {\"key\": value, ...}");
  Config c;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const auto& v = it.value();
    if (v.is_boolean())
      c.values_[it.key()] = v.get<bool>();
    else if (v.is_number())
      c.values_[it.key()] = v.get<double>();
    else if (v.is_string())
      c.values_[it.key()] = v.get<std::string>();
    else
      throw InputError(std::string(origin) + ": value of key '" + it.key() +
                       "' must be a string, a number or a boolean");
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
    if (!text.empty() && end == text.c_str() + text.size())
      c.values_[key] = d;
    else
      c.values_[key] = text;
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
  for (const auto& [k, v] : values_) std::visit([&](const auto& x) { j[k] = x; }, v);
  return j.dump();
}

}  // namespace corrlap

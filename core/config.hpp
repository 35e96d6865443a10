#pragma once
// Run-time configuration: a flat set of key -> value read from a JSON object or "key=value"
// strings. Unknown keys are errors, never silently ignored (check_keys).
#include <map>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace corrlap {

/// Documentation of one option of a discretization or a backend: name, default, meaning.
struct ParameterInfo {
  std::string name;
  std::string default_value;
  std::string description;
};

class Config {
 public:
  using Value = std::variant<bool, double, std::string>;

  Config() = default;
  /// A JSON object whose values are strings, numbers or booleans. Throws IoError/InputError.
  static Config from_json_file(const std::string& path);
  static Config from_json_string(std::string_view json, std::string_view origin = "config");
  /// "key=value" items; values parse as number or true/false when they look like one.
  static Config from_key_values(const std::vector<std::string>& items);

  /// Later values override earlier ones.
  void merge(const Config& other);
  void set(const std::string& key, Value value) { values_[key] = std::move(value); }
  bool has(const std::string& key) const { return values_.count(key) != 0; }
  bool empty() const { return values_.empty(); }
  std::vector<std::string> keys() const;
  /// The value of a present key (std::out_of_range otherwise), to copy it between configs.
  const Value& get_value(const std::string& key) const { return values_.at(key); }

  /// Typed getters: default when absent; InputError naming the key when the type is wrong.
  std::string get_string(const std::string& key, const std::string& fallback) const;
  double get_double(const std::string& key, double fallback) const;
  int get_int(const std::string& key, int fallback) const;
  bool get_bool(const std::string& key, bool fallback) const;

  /// Throws InputError naming every unknown key and listing the valid ones.
  void check_keys(const std::vector<std::string>& allowed, std::string_view context) const;

  /// check_keys against the names of documented parameters (a method's or a backend's).
  void check_parameters(const std::vector<ParameterInfo>& documented, std::string_view context) const;

  /// JSON text of the configuration (for logs and --json outputs).
  std::string to_json() const;

 private:
  std::map<std::string, Value> values_;
};

}  // namespace corrlap

#include "method_options.hpp"

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/core/parameters.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <cstdlib>

#include "deprecated.hpp"

namespace corrlap::cli {

std::vector<MethodFlag> method_flags() {
  struct Use {
    std::string method;
    Parameter parameter;
  };
  std::vector<std::string> order;
  std::map<std::string, std::vector<Use>> uses;
  for (const std::string& name : discretization_registry().names())
    for (const Parameter& p : make_discretization(name)->parameters().items()) {
      if (!uses.count(p.name)) order.push_back(p.name);
      uses[p.name].push_back({name, p});
    }
  std::vector<MethodFlag> flags;
  for (const std::string& name : order) {
    const std::vector<Use>& u = uses[name];
    // Methods that agree on allowed values and default share one clause of the help.
    std::vector<std::pair<std::string, std::string>> clauses;  // (methods, "allowed, default d")
    for (const Use& use : u) {
      const std::string allowed = use.parameter.allowed_text();
      const std::string clause = (allowed.empty() ? "" : allowed + ", ") + "default " + use.parameter.default_text();
      bool merged = false;
      for (auto& [methods, text] : clauses)
        if (text == clause) {
          methods += ", " + use.method;
          merged = true;
        }
      if (!merged) clauses.emplace_back(use.method, clause);
    }
    std::string help = u.front().parameter.doc;
    if (!u.front().parameter.math.empty()) help += " (docs/math.md " + u.front().parameter.math + ")";
    for (const auto& [methods, text] : clauses) help += "; " + methods + ": " + text;
    flags.push_back({name, flag_of(name), help, u.front().parameter.type == ParameterType::Boolean});
  }
  return flags;
}

void MethodOptions::add_options(CLI::App& cmd, bool method_flag, const std::string& default_method) {
  if (method_flag) {
    std::string names;
    for (const auto& n : discretization_registry().names()) names += (names.empty() ? "" : ", ") + n;
    method = default_method;
    method_option = cmd.add_option("--method", method, "discretization: " + names);
    if (default_method.empty())
      method_option->required();
    else
      method_option->capture_default_str();
  }
  for (const MethodFlag& f : method_flags()) {
    if (f.boolean)
      cmd.add_flag(f.flag, flag_booleans[f.parameter], f.help)->group("method parameters");
    else
      cmd.add_option(f.flag, flag_values[f.parameter], f.help)->group("method parameters");
  }
  cmd.add_option("--param", params, "method parameter key=value (repeatable; the flags above win)")
      ->group("method parameters");
  cmd.add_option("--method-config", config_file, "JSON object of method parameters (--param and the flags win)")
      ->group("method parameters");
}

Config MethodOptions::config(const std::string& for_method, bool only_declared) const {
  Config c;
  if (!config_file.empty()) c = Config::from_json_file(config_file);
  c.merge(Config::from_key_values(params));
  for (const auto& [name, text] : flag_values) {
    if (text.empty()) continue;
    // A number when the text is one, else the text: the method's declaration checks the type.
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() + text.size() && std::isfinite(v))
      c.set(name, v);
    else
      c.set(name, text);
  }
  for (const auto& [name, on] : flag_booleans)
    if (on) c.set(name, true);
  if (!only_declared) return c;
  const ParameterList& declared = make_discretization(for_method.empty() ? method : for_method)->parameters();
  Config mine;
  for (const std::string& key : c.keys())
    if (declared.find(key)) mine.set(key, c.get_value(key));
  return mine;
}

std::vector<std::string> MethodOptions::key_values() const {
  std::vector<std::string> items = params;
  for (const auto& [name, text] : flag_values)
    if (!text.empty()) items.push_back(name + "=" + text);
  for (const auto& [name, on] : flag_booleans)
    if (on) items.push_back(name + "=true");
  return items;
}

bool MethodOptions::any_given() const {
  if (!config_file.empty() || !params.empty() || (method_option && method_option->count() > 0)) return true;
  for (const auto& [name, text] : flag_values)
    if (!text.empty()) return true;
  for (const auto& [name, on] : flag_booleans)
    if (on) return true;
  return false;
}

}  // namespace corrlap::cli

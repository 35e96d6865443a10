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
    bool one_doc = true;
    for (const Use& use : u) one_doc = one_doc && use.parameter.doc == u.front().parameter.doc;
    // Methods that agree (on the doc when it differs, the allowed values and the default) share
    // one clause of the help.
    std::vector<std::pair<std::string, std::string>> clauses;  // (methods, clause)
    for (const Use& use : u) {
      const Parameter& p = use.parameter;
      const std::string allowed = p.type == ParameterType::Boolean ? "" : p.allowed_text();
      std::string clause =
          (one_doc ? "" : p.doc + "; ") + (allowed.empty() ? "" : allowed + ", ") + "default " + p.default_text();
      if (!one_doc && !p.math.empty()) clause += " (docs/math.md " + p.math + ")";
      bool merged = false;
      for (auto& [methods, text] : clauses)
        if (text == clause) {
          methods += ", " + use.method;
          merged = true;
        }
      if (!merged) clauses.emplace_back(use.method, clause);
    }
    const Parameter& first = u.front().parameter;
    std::string help;
    if (one_doc) help = first.doc + (first.math.empty() ? "" : " (docs/math.md " + first.math + ")");
    for (const auto& [methods, text] : clauses) help += (help.empty() ? "" : "; ") + methods + ": " + text;
    std::string type_name = "X";
    if (first.type == ParameterType::Integer) type_name = "N";
    if (first.type == ParameterType::Choice) {
      type_name.clear();
      for (const Use& use : u)
        for (const std::string& c : use.parameter.choices)
          if (("|" + type_name + "|").find("|" + c + "|") == std::string::npos)
            type_name += (type_name.empty() ? "" : "|") + c;
    }
    flags.push_back({name, flag_of(name), help, type_name, first.type == ParameterType::Boolean});
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
      cmd.add_option(f.flag, flag_values[f.parameter], f.help)->type_name(f.type_name)->group("method parameters");
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

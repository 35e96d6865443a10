#pragma once
// Typed parameters: a method declares each of its parameters once (name, type, default, allowed
// values or range, a one-line doc, the docs/math.md section), and everything else is derived from
// that declaration: the validation of a Config (one wording for unknown keys, wrong types and
// out-of-range values), the typed reads inside the method, the CLI flags and their help, the Python
// keywords and the docs table (docs/discretizations.md, checked by a test).
//
//   const ParameterList params = {
//       Parameter::real("lambda", 1.0, "stabilization weight of M1", "§2.2").at_least(0.0),
//       Parameter::choice("mass", {"full", "lumped"}, "mass matrix", "§4.4"),
//   };
//   const ParameterValues p = params.read(config, "polydec");  // InputError on any bad key or value
//   const double lambda = p.real("lambda");                    // the given value or the default
#include <initializer_list>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config.hpp"

namespace corrlap {

enum class ParameterType { Real, Integer, Boolean, Choice };
/// "real" | "integer" | "boolean" | "choice".
const char* to_string(ParameterType type);

/// One declared parameter.
struct Parameter {
  std::string name;
  ParameterType type = ParameterType::Real;
  /// The default as text ("0.1", "full", "false"); empty when the method computes it from the
  /// input (then `default_doc` says how, e.g. "0.1 h^(2/3)").
  std::string default_value;
  std::string default_doc;
  std::vector<std::string> choices;  ///< Choice: the allowed values, the default first
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false, max_open = false;  ///< open interval ends: (min, ...) instead of [min, ...]
  std::string doc;                          ///< one line
  std::string math;                         ///< docs/math.md section ("§2.2"), empty for extensions

  static Parameter real(std::string name, double default_value, std::string doc, std::string math = {});
  /// A real whose default the method computes (`how`, e.g. "0.1 h^(2/3)").
  static Parameter computed_real(std::string name, std::string how, std::string doc, std::string math = {});
  static Parameter integer(std::string name, int default_value, std::string doc, std::string math = {});
  static Parameter boolean(std::string name, bool default_value, std::string doc, std::string math = {});
  /// `values` are the allowed values; the first is the default.
  static Parameter choice(std::string name, std::vector<std::string> values, std::string doc, std::string math = {});

  /// Range builders (Real and Integer): [v, ...), (v, ...), (..., v], (..., v).
  Parameter at_least(double v) &&;
  Parameter above(double v) &&;
  Parameter at_most(double v) &&;
  Parameter below(double v) &&;

  /// The default as the docs show it: the value, or `default_doc` for computed ones.
  std::string default_text() const;
  /// "> 0", "[0, 1)", "full | lumped", "true | false", or "" when any value of the type is allowed.
  std::string allowed_text() const;
};

class ParameterValues;

/// The parameters of one method (or any other configurable piece), in declaration order.
class ParameterList {
 public:
  ParameterList() = default;
  ParameterList(std::initializer_list<Parameter> items) : items_(items) {}
  explicit ParameterList(std::vector<Parameter> items) : items_(std::move(items)) {}

  /// Appends `more` (e.g. the normal-policy parameters every corrected method shares).
  ParameterList& append(const ParameterList& more);

  const std::vector<Parameter>& items() const { return items_; }
  bool empty() const { return items_.empty(); }
  /// nullptr when no parameter has this name.
  const Parameter* find(std::string_view name) const;
  std::vector<std::string> names() const;
  /// Name, default text and doc of every parameter (the listing `corrlap backends` also uses).
  std::vector<ParameterInfo> info() const;

  /// Checks every key of `config` against the declarations: unknown keys (listing the valid
  /// ones), wrong types, values out of range or not among the choices are InputErrors starting
  /// with `context` (e.g. the method name) and tagged with the parameter's name. Returns the values
  /// to read from; they refer to this list and to `config`, which must outlive them.
  ParameterValues read(const Config& config, std::string_view context) const;

 private:
  std::vector<Parameter> items_;
};

/// A validated Config read through its declarations: the given value, else the declared default.
/// Reading a name that is not declared, or with the wrong type, is a programming error
/// (std::logic_error), never a user error.
class ParameterValues {
 public:
  double real(std::string_view name) const;
  /// The given value, or nothing for a computed default.
  std::optional<double> optional_real(std::string_view name) const;
  int integer(std::string_view name) const;
  bool boolean(std::string_view name) const;
  std::string choice(std::string_view name) const;
  bool given(std::string_view name) const;
  const Config& config() const { return *config_; }

 private:
  friend class ParameterList;
  ParameterValues(const ParameterList& list, const Config& config) : list_(&list), config_(&config) {}
  const Parameter& declared(std::string_view name, ParameterType type) const;
  const ParameterList* list_;
  const Config* config_;
};

}  // namespace corrlap

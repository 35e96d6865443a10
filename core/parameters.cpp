#include "parameters.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "error.hpp"

namespace corrlap {

const char* to_string(ParameterType type) {
  switch (type) {
    case ParameterType::Real:
      return "real";
    case ParameterType::Integer:
      return "integer";
    case ParameterType::Boolean:
      return "boolean";
    case ParameterType::Choice:
      return "choice";
  }
  return "?";
}

namespace {

// Shortest text that reads back as the same double ("0.1", "1e-12", "0.66666666666666663").
std::string number_text(double v) {
  for (int precision = 1; precision <= 17; ++precision) {
    std::ostringstream os;
    os.precision(precision);
    os << v;
    if (std::stod(os.str()) == v) return os.str();
  }
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

Parameter make(std::string name, ParameterType type, std::string default_value, std::string doc, std::string math) {
  Parameter p;
  p.name = std::move(name);
  p.type = type;
  p.default_value = std::move(default_value);
  p.doc = std::move(doc);
  p.math = std::move(math);
  return p;
}

bool in_range(const Parameter& p, double v) {
  if (p.min_open ? !(v > p.min) : !(v >= p.min)) return false;
  if (p.max_open ? !(v < p.max) : !(v <= p.max)) return false;
  return true;
}

// The text of a given value as the user wrote it (for messages).
std::string given_text(const Config& config, const std::string& key) { return config.get_string(key, ""); }

[[noreturn]] void reject(std::string_view context, const Parameter& p, const std::string& value,
                         const std::string& expected) {
  throw InputError(std::string(context) + ": " + p.name + " = " + value + ": expected " + expected, p.name);
}

}  // namespace

Parameter Parameter::real(std::string name, double default_value, std::string doc, std::string math) {
  return make(std::move(name), ParameterType::Real, number_text(default_value), std::move(doc), std::move(math));
}

Parameter Parameter::computed_real(std::string name, std::string how, std::string doc, std::string math) {
  Parameter p = make(std::move(name), ParameterType::Real, "", std::move(doc), std::move(math));
  p.default_doc = std::move(how);
  return p;
}

Parameter Parameter::integer(std::string name, int default_value, std::string doc, std::string math) {
  Parameter p =
      make(std::move(name), ParameterType::Integer, std::to_string(default_value), std::move(doc), std::move(math));
  p.min = -2147483648.0;
  p.max = 2147483647.0;
  return p;
}

Parameter Parameter::boolean(std::string name, bool default_value, std::string doc, std::string math) {
  return make(std::move(name), ParameterType::Boolean, default_value ? "true" : "false", std::move(doc),
              std::move(math));
}

Parameter Parameter::choice(std::string name, std::vector<std::string> values, std::string doc, std::string math) {
  if (values.empty()) throw std::logic_error("Parameter::choice '" + name + "': no value");
  Parameter p = make(std::move(name), ParameterType::Choice, values.front(), std::move(doc), std::move(math));
  p.choices = std::move(values);
  return p;
}

Parameter Parameter::at_least(double v) && {
  min = v;
  min_open = false;
  return std::move(*this);
}
Parameter Parameter::above(double v) && {
  min = v;
  min_open = true;
  return std::move(*this);
}
Parameter Parameter::at_most(double v) && {
  max = v;
  max_open = false;
  return std::move(*this);
}
Parameter Parameter::below(double v) && {
  max = v;
  max_open = true;
  return std::move(*this);
}

std::string Parameter::default_text() const { return default_value.empty() ? default_doc : default_value; }

std::string Parameter::allowed_text() const {
  switch (type) {
    case ParameterType::Boolean:
      return "true | false";
    case ParameterType::Choice: {
      std::string s;
      for (const auto& c : choices) s += (s.empty() ? "" : " | ") + c;
      return s;
    }
    case ParameterType::Real:
    case ParameterType::Integer:
      break;
  }
  // Integers carry the int range as their bounds; only tighter bounds are worth saying.
  const bool has_min = type == ParameterType::Integer ? min > -2147483648.0 : std::isfinite(min);
  const bool has_max = type == ParameterType::Integer ? max < 2147483647.0 : std::isfinite(max);
  if (has_min && has_max)
    return std::string(min_open ? "(" : "[") + number_text(min) + ", " + number_text(max) + (max_open ? ")" : "]");
  if (has_min) return std::string(min_open ? "> " : ">= ") + number_text(min);
  if (has_max) return std::string(max_open ? "< " : "<= ") + number_text(max);
  return "";
}

ParameterList& ParameterList::append(const ParameterList& more) {
  items_.insert(items_.end(), more.items_.begin(), more.items_.end());
  return *this;
}

const Parameter* ParameterList::find(std::string_view name) const {
  for (const auto& p : items_)
    if (p.name == name) return &p;
  return nullptr;
}

std::vector<std::string> ParameterList::names() const {
  std::vector<std::string> n;
  n.reserve(items_.size());
  for (const auto& p : items_) n.push_back(p.name);
  return n;
}

std::vector<ParameterInfo> ParameterList::info() const {
  std::vector<ParameterInfo> out;
  out.reserve(items_.size());
  for (const auto& p : items_) {
    std::string description = p.doc;
    if (const std::string allowed = p.allowed_text(); !allowed.empty() && p.type != ParameterType::Boolean)
      description += " (" + allowed + ")";
    if (!p.math.empty()) description += " [docs/math.md " + p.math + "]";
    out.push_back({p.name, p.default_text(), description});
  }
  return out;
}

ParameterValues ParameterList::read(const Config& config, std::string_view context) const {
  config.check_keys(names(), context);
  for (const std::string& key : config.keys()) {
    const Parameter& p = *find(key);
    const std::string text = given_text(config, key);
    switch (p.type) {
      case ParameterType::Real:
      case ParameterType::Integer: {
        double v = 0.0;
        try {
          v = config.get_double(key, 0.0);
        } catch (const InputError&) {
          reject(context, p, "'" + text + "'", p.type == ParameterType::Real ? "a number" : "an integer");
        }
        if (!std::isfinite(v)) reject(context, p, text, "a finite number");
        if (p.type == ParameterType::Integer && v != std::floor(v)) reject(context, p, text, "an integer");
        if (!in_range(p, v)) reject(context, p, text, p.allowed_text());
        break;
      }
      case ParameterType::Boolean:
        try {
          (void)config.get_bool(key, false);
        } catch (const InputError&) {
          reject(context, p, "'" + text + "'", "true or false");
        }
        break;
      case ParameterType::Choice:
        if (std::find(p.choices.begin(), p.choices.end(), text) == p.choices.end())
          reject(context, p, "'" + text + "'", "one of " + p.allowed_text());
        break;
    }
  }
  return ParameterValues(*this, config);
}

const Parameter& ParameterValues::declared(std::string_view name, ParameterType type) const {
  const Parameter* p = list_->find(name);
  if (!p) throw std::logic_error("parameter '" + std::string(name) + "' is not declared");
  if (p->type != type)
    throw std::logic_error("parameter '" + std::string(name) + "' is " + to_string(p->type) + ", read as " +
                           to_string(type));
  return *p;
}

double ParameterValues::real(std::string_view name) const {
  const Parameter& p = declared(name, ParameterType::Real);
  if (config_->has(p.name)) return config_->get_double(p.name, 0.0);
  if (p.default_value.empty())
    throw std::logic_error("parameter '" + p.name + "' has a computed default: read it with optional_real");
  return std::stod(p.default_value);
}

std::optional<double> ParameterValues::optional_real(std::string_view name) const {
  const Parameter& p = declared(name, ParameterType::Real);
  if (config_->has(p.name)) return config_->get_double(p.name, 0.0);
  if (p.default_value.empty()) return std::nullopt;
  return std::stod(p.default_value);
}

int ParameterValues::integer(std::string_view name) const {
  const Parameter& p = declared(name, ParameterType::Integer);
  return config_->has(p.name) ? config_->get_int(p.name, 0) : std::stoi(p.default_value);
}

bool ParameterValues::boolean(std::string_view name) const {
  const Parameter& p = declared(name, ParameterType::Boolean);
  return config_->get_bool(p.name, p.default_value == "true");
}

std::string ParameterValues::choice(std::string_view name) const {
  const Parameter& p = declared(name, ParameterType::Choice);
  return config_->get_string(p.name, p.default_value);
}

bool ParameterValues::given(std::string_view name) const {
  (void)list_->find(name);
  return config_->has(std::string(name));
}

}  // namespace corrlap

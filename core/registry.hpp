#pragma once
// Run-time choice by name: discretizations, linear solvers and eigen solvers register a factory
// under a name; users pick one from a config or the command line.
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "error.hpp"

namespace corrlap {

template <class Interface>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Interface>()>;
  struct Entry {
    std::string description;
    Factory factory;
  };

  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  void add(const std::string& name, std::string description, Factory factory) {
    entries_[name] = Entry{std::move(description), std::move(factory)};
  }
  bool contains(const std::string& name) const { return entries_.count(name) != 0; }
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const auto& [k, v] : entries_) n.push_back(k);
    return n;
  }
  const std::string& description(const std::string& name) const { return find(name).description; }
  /// Throws InputError listing the valid names when `name` is unknown.
  std::unique_ptr<Interface> create(const std::string& name) const { return find(name).factory(); }

 private:
  const Entry& find(const std::string& name) const {
    auto it = entries_.find(name);
    if (it == entries_.end()) {
      std::ostringstream os;
      os << "unknown " << kind_ << " '" << name << "'; available:";
      for (const auto& [k, v] : entries_) os << " " << k;
      throw InputError(os.str());
    }
    return it->second;
  }
  std::string kind_;
  std::map<std::string, Entry> entries_;
};

}  // namespace corrlap

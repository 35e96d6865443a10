// corrlap backends: the linear solver and eigen solver backends with their options.
#include <corrlap/backends/registry.hpp>
#include <iostream>
#include <nlohmann/json.hpp>

#include "command.hpp"

namespace corrlap::cli {
namespace {

template <class Registry>
nlohmann::json describe(const Registry& registry) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& name : registry.names()) {
    auto backend = registry.create(name);
    nlohmann::json opts = nlohmann::json::array();
    for (const auto& o : backend->options())
      opts.push_back({{"name", o.name}, {"default", o.default_value}, {"description", o.description}});
    list.push_back({{"name", name}, {"description", registry.description(name)}, {"options", opts}});
  }
  return list;
}

void print(const nlohmann::json& list, const char* title) {
  std::cout << title << ":\n";
  for (const auto& b : list) {
    std::cout << "  " << b["name"].get<std::string>() << "  -  " << b["description"].get<std::string>() << "\n";
    for (const auto& o : b["options"])
      std::cout << "      " << o["name"].get<std::string>() << " = " << o["default"].get<std::string>() << "    "
                << o["description"].get<std::string>() << "\n";
  }
}

RegisterCommand reg(45, "backends", [](CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand("backends", "list the linear solver and eigen solver backends and their options");
  cmd->add_flag("--json", *json, "print a JSON object");
  cmd->callback([json] {
    const nlohmann::json linear = describe(linear_solver_registry());
    const nlohmann::json eigen = describe(eigen_solver_registry());
    if (*json) {
      std::cout << nlohmann::json{{"linear_solvers", linear}, {"eigen_solvers", eigen}}.dump(
                       2, ' ', false, nlohmann::json::error_handler_t::replace)
                << "\n";
      return;
    }
    print(linear, "linear solvers (config key \"solver\")");
    print(eigen, "eigen solvers");
    std::cout << "Options are given with --solver-option key=value or a JSON file (--solver-config), e.g.\n"
                 "  {\"solver\": \"cholmod\", \"ordering\": \"metis\", \"supernodal\": \"auto\"}\n";
  });
});

}  // namespace
}  // namespace corrlap::cli

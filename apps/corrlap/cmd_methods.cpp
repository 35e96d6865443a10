// corrlap methods: the discretizations with the normals they need and their parameters, from the
// declarations (core/parameters.hpp); --markdown prints the table of docs/discretizations.md.
#include <corrlap/core/parameters.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <iostream>
#include <nlohmann/json.hpp>

#include "command.hpp"
#include "deprecated.hpp"

namespace corrlap::cli {
namespace {

const char* normals_needed(NormalKind kind) {
  return kind == NormalKind::Face ? "face" : kind == NormalKind::Vertex ? "vertex" : "none";
}

struct MethodsArgs {
  bool json = false, markdown = false;
};

void run(const MethodsArgs& a) {
  if (a.markdown) {
    std::cout << method_parameters_markdown();
    return;
  }
  const DiscretizationRegistry& registry = discretization_registry();
  nlohmann::json list = nlohmann::json::array();
  for (const std::string& name : registry.names()) {
    const auto d = make_discretization(name);
    nlohmann::json params = nlohmann::json::array();
    for (const Parameter& p : d->parameters().items())
      params.push_back({{"name", p.name},
                        {"flag", flag_of(p.name)},
                        {"type", to_string(p.type)},
                        {"default", p.default_text()},
                        {"allowed", p.allowed_text()},
                        {"description", p.doc},
                        {"math", p.math}});
    list.push_back({{"name", name},
                    {"description", registry.description(name)},
                    {"normals", normals_needed(d->required_normals())},
                    {"parameters", params}});
  }
  if (a.json) {
    std::cout << list.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return;
  }
  for (const auto& m : list) {
    std::cout << m["name"].get<std::string>() << "  -  " << m["description"].get<std::string>()
              << " (normals: " << m["normals"].get<std::string>() << ")\n";
    for (const auto& p : m["parameters"]) {
      std::cout << "    " << p["flag"].get<std::string>() << " (" << p["type"].get<std::string>() << ", default "
                << p["default"].get<std::string>();
      if (!p["allowed"].get<std::string>().empty()) std::cout << ", " << p["allowed"].get<std::string>();
      std::cout << ")  " << p["description"].get<std::string>() << "\n";
    }
  }
  std::cout << "Every parameter is a flag of operators, eigs, solve, regularize, reconstruct and study, or\n"
               "--param key=value, or a key of a --method-config JSON file.\n";
}

RegisterCommand reg(44, "methods", [](CLI::App& app) {
  auto args = std::make_shared<MethodsArgs>();
  auto* cmd = app.add_subcommand("methods", "list the discretizations, the normals they need and their parameters");
  cmd->add_flag("--json", args->json, "print a JSON array");
  cmd->add_flag("--markdown", args->markdown, "print the parameter table of docs/discretizations.md");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

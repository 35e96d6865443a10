#pragma once
// Registry of the built-in discretizations, by name (polydec, projected-polydec, interpolated,
// fem, vrm, corrected-vrm, heat-kernel, cotan).
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/registry.hpp>
#include <string>

namespace corrlap {

using DiscretizationRegistry = Registry<Discretization>;

/// The process-wide registry, filled with every built-in method on first use. Thread-safe to read.
DiscretizationRegistry& discretization_registry();

/// Shortcut: discretization_registry().create(name).
std::unique_ptr<Discretization> make_discretization(const std::string& name);

/// The parameters of every registered method as a Markdown table (method, parameter, type,
/// default, allowed values, meaning, docs/math.md section), rendered from the declarations: the
/// table of docs/discretizations.md ("Parameters"), which a test keeps equal to this.
std::string method_parameters_markdown();

}  // namespace corrlap

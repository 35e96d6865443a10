#pragma once
// Registry of the built-in discretizations, by name (polydec, projected-polydec, interpolated,
// fem, vrm, corrected-vrm, heat-kernel, cotan).
#include <corrlap/core/discretization.hpp>
#include <corrlap/core/registry.hpp>

namespace corrlap {

using DiscretizationRegistry = Registry<Discretization>;

/// The process-wide registry, filled with every built-in method on first use. Thread-safe to read.
DiscretizationRegistry& discretization_registry();

/// Shortcut: discretization_registry().create(name).
std::unique_ptr<Discretization> make_discretization(const std::string& name);

}  // namespace corrlap

#pragma once
// The module corrlap._core is bound stage by stage, one file each (surface, normals, operators,
// solvers, regularization); the Python package corrlap (python/corrlap/__init__.py) wraps it with
// keyword arguments, scipy matrices and the docstrings.
#include <pybind11/pybind11.h>

#include <corrlap/core/voxel_grid.hpp>
#include <corrlap/regularization/regularize_surface.hpp>
#include <optional>
#include <string>

namespace corrlap::python {

namespace py = pybind11;

void bind_surface(py::module_& m);
void bind_normals(py::module_& m);
void bind_operators(py::module_& m);
void bind_solvers(py::module_& m);
void bind_regularization(py::module_& m);
void bind_view(py::module_& m);

/// Voxels of an implicit shape (a name of `corrlap digitize --shape`, or a polynomial) digitized as
/// the CLI does (docs/math.md §1.2).
VoxelGrid shape_voxels(const std::string& shape, double h, double bbox_min, double bbox_max, int offset,
                       py::handle center);
/// Voxels of a 3D array indexed volume[x, y, z], inside = value > threshold, centred as the CLI
/// centres a volume file (docs/io.md); no h: the longest side spans 2.
VoxelGrid array_voxels(py::handle volume, std::optional<double> h, double threshold);

/// The options of regularize and regularize_volume from their common keywords (regularization.cpp);
/// unset curvature_radius, curvature_spacing and size keep the library's defaults.
/// alpha0: a number, or nullopt for the library's automatic choice (RegularizationOptions::alpha0_auto).
RegularizationOptions regularization_options_arg(const std::string& method, const py::dict& params,
                                                 std::optional<double> alpha0, std::optional<double> curvature_radius,
                                                 std::optional<double> curvature_spacing, std::optional<double> size,
                                                 const std::string& solver, const py::dict& solver_options,
                                                 std::optional<double> solve_accuracy);

}  // namespace corrlap::python

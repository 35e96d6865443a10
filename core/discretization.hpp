#pragma once
// The Discretization contract: surface mesh + normal fields + parameters -> sparse operators.
//
// Sign convention (spec §0), the same everywhere in corrlap:
//   L is NEGATIVE semi-definite: L 1 = 0, u^T L u <= 0, M^{-1} L approximates the Laplace-Beltrami
//   operator (sum of second derivatives), and the generalized eigenvalues of L u = lambda M u are
//   <= 0 (-lambda ~ l(l+1) on the unit sphere).
#include <Eigen/Sparse>
#include <optional>
#include <string>
#include <vector>

#include "config.hpp"
#include "normal_fields.hpp"
#include "surfel_mesh.hpp"

namespace corrlap {

/// Output of a discretization. Matrices are #V x #V on vertices (or #F x #F for operators on
/// surfels, see `domain`). Optional pieces are present where the method defines them.
struct Operators {
  enum class Domain { Vertices, Faces };

  Eigen::SparseMatrix<double> L;  ///< stiffness, negative semi-definite (spec §0)
  Eigen::SparseMatrix<double> M;  ///< mass, symmetric positive definite for consistent normals
  std::optional<Eigen::SparseMatrix<double>> M_lumped;  ///< diagonal mass
  std::optional<Eigen::SparseMatrix<double>> D0;        ///< #E x #V exterior derivative
  std::optional<Eigen::SparseMatrix<double>> sharp;     ///< 3#F x #E, rows 3f+c
  std::optional<Eigen::SparseMatrix<double>> flat;      ///< #E x 3#F
  std::optional<Eigen::SparseMatrix<double>> M1;        ///< #E x #E one-form inner product
  Domain domain = Domain::Vertices;
  std::vector<std::string> warnings;  ///< e.g. normals inconsistent with the surfel orientation
};

/// What a policy does with normals inconsistent with the surfel orientation (u.n <= 0).
enum class OrientationPolicy { Error, Warn, Clamp };

class Discretization {
 public:
  virtual ~Discretization() = default;
  /// Registry name, e.g. "fem".
  virtual std::string name() const = 0;
  /// Normal field the method needs (NormalKind::None for uncorrected methods).
  virtual NormalKind required_normals() const = 0;
  /// Accepted parameters with their defaults (the reference's).
  virtual std::vector<ParameterInfo> parameters() const = 0;
  /// Builds the operators. Throws InputError on missing or invalid normals, unknown parameter
  /// keys, or an invalid mesh.
  virtual Operators assemble(const SurfelMesh& mesh, const NormalFields& normals,
                             const Config& params) const = 0;
};

}  // namespace corrlap

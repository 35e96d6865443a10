#pragma once
// The Discretization contract: surface mesh + normal fields + parameters -> sparse operators.
//
// Sign convention (docs/math.md §0), the same everywhere in corrlap:
//   L is NEGATIVE semi-definite: L 1 = 0, u^T L u <= 0, M^{-1} L approximates the Laplace-Beltrami
//   operator (sum of second derivatives), and the generalized eigenvalues of L u = lambda M u are
//   <= 0 (-lambda ~ l(l+1) on the unit sphere).
#include <Eigen/Sparse>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "config.hpp"
#include "normal_fields.hpp"
#include "parameters.hpp"
#include "surfel_mesh.hpp"

namespace corrlap {

/// Output of a discretization. Matrices are #V x #V on vertices (or #F x #F for operators on
/// surfels, see `domain`). Optional pieces are present where the method defines them.
struct Operators {
  enum class Domain { Vertices, Faces };

  Eigen::SparseMatrix<double> L;                        ///< stiffness, negative semi-definite (docs/math.md §0)
  Eigen::SparseMatrix<double> M;                        ///< mass, symmetric positive definite for consistent normals
  std::optional<Eigen::SparseMatrix<double>> M_lumped;  ///< diagonal mass
  std::optional<Eigen::SparseMatrix<double>> D0;        ///< #E x #V exterior derivative
  std::optional<Eigen::SparseMatrix<double>> sharp;     ///< 3#F x #E, rows 3f+c
  std::optional<Eigen::SparseMatrix<double>> flat;      ///< #E x 3#F
  std::optional<Eigen::SparseMatrix<double>> M1;        ///< #E x #E one-form inner product
  Domain domain = Domain::Vertices;
  std::vector<std::string> warnings;  ///< e.g. normals inconsistent with the surfel orientation
  /// Non-empty when L or M may break the properties documented above (L negative semi-definite,
  /// M positive definite): what was computed as given and why. A solver failing on these
  /// operators should name it (the CLI does). Empty for operators that keep the contract.
  std::string contract_risk;
};

/// Empties everything but the storage of L and M, for a method that refills `ops` (assemble_into).
inline void reset_for_reuse(Operators& ops) {
  ops.M_lumped.reset();
  ops.D0.reset();
  ops.sharp.reset();
  ops.flat.reset();
  ops.M1.reset();
  ops.domain = Operators::Domain::Vertices;
  ops.warnings.clear();
  ops.contract_risk.clear();
}

/// Moves every field of `from` into `out` (L and M by swap: Eigen 3.4's SparseMatrix has no move
/// assignment, and a copy would double the peak memory), for a method that computes its operators
/// elsewhere and refills `out`. This and reset_for_reuse are the two places that list the fields.
inline void move_operators(Operators& from, Operators& out) {
  out.L.swap(from.L);
  out.M.swap(from.M);
  out.M_lumped = std::move(from.M_lumped);
  out.D0 = std::move(from.D0);
  out.sharp = std::move(from.sharp);
  out.flat = std::move(from.flat);
  out.M1 = std::move(from.M1);
  out.domain = from.domain;
  out.warnings = std::move(from.warnings);
  out.contract_risk = std::move(from.contract_risk);
}

/// What a policy does with normals inconsistent with the surfel orientation (u.n <= 0).
enum class OrientationPolicy { Error, Warn, Clamp };

/// Symbolic part of the vertex assembly of a quad mesh (discretizations/assembly/quad_pattern.hpp),
/// built once per connectivity by the caller and passed to assemble / assemble_into. Declared here
/// so that core does not depend on discretizations.
class QuadPattern;

/// A discretization: name, the normals it needs, its declared parameters, and one assembly entry
/// point, `assemble_into`. The `assemble` overloads are non-virtual conveniences over it, so every
/// path (one-shot, with a pattern, refill) runs the same code and fills every field of Operators.
class Discretization {
 public:
  virtual ~Discretization() = default;
  /// Registry name, e.g. "fem".
  virtual std::string name() const = 0;
  /// Normal field the method needs (NormalKind::None for uncorrected methods).
  virtual NormalKind required_normals() const = 0;
  /// The method's parameters, declared once (core/parameters.hpp): names, types, defaults (the
  /// reference's), allowed values, docs.
  virtual const ParameterList& parameters() const = 0;

  /// Builds the operators into `out`. Every field of `out` is replaced; the storage of out.L and
  /// out.M is reused when it is large enough, so repeated assembly on one mesh (a regularization
  /// loop, a study) fills memory that is already mapped. `pattern` (nullptr = none) is used by the
  /// quad methods that gather by vertex (fem, polydec, projected-polydec, interpolated, vrm,
  /// corrected-vrm) and ignored by the others; the result is bitwise the same with or without it
  /// (InputError if it was built for another connectivity). Throws InputError on missing or
  /// invalid normals, unknown or invalid parameters (ParameterList::read), or an invalid mesh.
  virtual void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& params,
                             const QuadPattern* pattern, Operators& out) const = 0;

  /// One-shot: a fresh Operators, no pattern.
  Operators assemble(const SurfelMesh& mesh, const NormalFields& normals, const Config& params) const {
    Operators ops;
    assemble_into(mesh, normals, params, nullptr, ops);
    return ops;
  }
  /// A fresh Operators through `pattern`.
  Operators assemble(const SurfelMesh& mesh, const NormalFields& normals, const Config& params,
                     const QuadPattern& pattern) const {
    Operators ops;
    assemble_into(mesh, normals, params, &pattern, ops);
    return ops;
  }
  /// Refill without a pattern.
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& params, Operators& out) const {
    assemble_into(mesh, normals, params, nullptr, out);
  }
  /// Refill through `pattern`.
  void assemble_into(const SurfelMesh& mesh, const NormalFields& normals, const Config& params,
                     const QuadPattern& pattern, Operators& out) const {
    assemble_into(mesh, normals, params, &pattern, out);
  }
};

}  // namespace corrlap

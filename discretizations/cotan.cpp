#include "cotan.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <corrlap/core/error.hpp>
#include <corrlap/discretizations/assembly/parallel_assembly.hpp>
#include <sstream>
#include <vector>

#include "triangle_kernels.hpp"

namespace corrlap {

Operators assemble_cotan(const Eigen::MatrixX3d& V, const TriangleIndices& T, CotanMass mass) {
  const Eigen::Index nv = V.rows(), nt = T.rows();
  if (nt == 0) throw InputError("cotan: the mesh has no triangle");
  if (!V.allFinite()) throw InputError("cotan: non-finite vertex position");
  for (Eigen::Index t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k)
      if (T(t, k) < 0 || T(t, k) >= nv) {
        std::ostringstream os;
        os << "cotan: triangle " << t << " refers to vertex " << T(t, k) << " outside [0, " << nv << ")";
        throw InputError(os.str());
      }
    if (T(t, 0) == T(t, 1) || T(t, 1) == T(t, 2) || T(t, 0) == T(t, 2))
      throw InputError("cotan: triangle " + std::to_string(t) + " repeats a vertex");
  }
  std::vector<double> K(std::size_t(nt) * 9), Mloc(std::size_t(nt) * 9, 0.0);
  std::vector<char> degenerate(std::size_t(nt), 0);
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, nt, 1024), [&](const auto& r) {
    for (Eigen::Index t = r.begin(); t != r.end(); ++t) {
      const Eigen::Vector3d x0 = V.row(T(t, 0)), x1 = V.row(T(t, 1)), x2 = V.row(T(t, 2));
      const double l0 = (x2 - x1).norm(), l1 = (x2 - x0).norm(), l2 = (x1 - x0).norm();
      const double lmax = std::max({l0, l1, l2});
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> Kt(&K[std::size_t(t) * 9]);
      Eigen::Matrix3d k;
      if (heron_area(l0, l1, l2) <= 1e-15 * lmax * lmax || !cotan_triangle_stiffness(l0, l1, l2, k)) {
        degenerate[std::size_t(t)] = 1;
        Kt.setZero();
        continue;
      }
      Kt = k;
      Eigen::Vector3d m;
      if (mass == CotanMass::Voronoi)
        m = mixed_voronoi_triangle_mass(x0, x1, x2);
      else
        m = Eigen::Vector3d::Constant(0.5 * (x1 - x0).cross(x2 - x0).norm() / 3.0);
      for (int a = 0; a < 3; ++a) Mloc[std::size_t(t) * 9 + std::size_t(a) * 4] = m[a];
    }
  });
  for (Eigen::Index t = 0; t < nt; ++t)
    if (degenerate[std::size_t(t)]) {
      std::ostringstream os;
      os << "cotan: triangle " << t << " (vertices " << T(t, 0) << ", " << T(t, 1) << ", " << T(t, 2)
         << ") has zero area";
      throw InputError(os.str());
    }
  const AssemblyPlan plan(T.data(), std::size_t(nt), 3, int(nv));
  Operators ops;
  ops.L = plan.gather(K.data());
  ops.L *= -1.0;  // docs/math.md §0: negative semi-definite
  // The mass is diagonal: sum per vertex in triangle order (deterministic), without the plan's
  // structural off-diagonal zeros.
  Eigen::VectorXd d = Eigen::VectorXd::Zero(nv);
  for (Eigen::Index t = 0; t < nt; ++t)
    for (int a = 0; a < 3; ++a) d[T(t, a)] += Mloc[std::size_t(t) * 9 + std::size_t(a) * 4];
  for (Eigen::Index v = 0; v < nv; ++v)
    if (!(d[v] > 0)) throw InputError("cotan: vertex " + std::to_string(v) + " belongs to no triangle");
  ops.M.resize(nv, nv);
  ops.M.reserve(Eigen::VectorXi::Ones(nv));
  for (Eigen::Index v = 0; v < nv; ++v) ops.M.insert(v, v) = d[v];
  ops.M.makeCompressed();
  return ops;
}

namespace {

class Cotan final : public Discretization {
 public:
  std::string name() const override { return "cotan"; }
  NormalKind required_normals() const override { return NormalKind::None; }
  const ParameterList& parameters() const override {
    static const ParameterList list = {Parameter::choice(
        "mass", {"voronoi", "barycentric"}, "lumped mass: voronoi (mixed Voronoi, Meyer et al.) | barycentric (A/3)")};
    return list;
  }
  void assemble_into(const SurfelMesh& mesh, const NormalFields&, const Config& config, const QuadPattern*,
                     Operators& out) const override {
    const ParameterValues params = parameters().read(config, name());
    mesh.validate("cotan");
    const std::string m = params.choice("mass");
    TriangleIndices T(2 * mesh.num_faces(), 3);
    for (int f = 0; f < mesh.num_faces(); ++f) {  // split along x0-x2 (documented in cotan.hpp)
      T.row(2 * f) << mesh.faces(f, 0), mesh.faces(f, 1), mesh.faces(f, 2);
      T.row(2 * f + 1) << mesh.faces(f, 0), mesh.faces(f, 2), mesh.faces(f, 3);
    }
    Operators ops = assemble_cotan(mesh.positions, T, m == "voronoi" ? CotanMass::Voronoi : CotanMass::Barycentric);
    move_operators(ops, out);
  }
};

}  // namespace

std::unique_ptr<Discretization> make_cotan() { return std::make_unique<Cotan>(); }

}  // namespace corrlap

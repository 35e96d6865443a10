// Linear and eigen solvers by name with keyword options (the CLI's Config, strict keys): solve, eigs, backends.
#include <corrlap/backends/registry.hpp>
#include <corrlap/core/error.hpp>

#include "bindings.hpp"
#include "convert.hpp"

namespace corrlap::python {
namespace {

template <class Registry>
py::dict describe(const Registry& registry) {
  py::dict out;
  for (const auto& name : registry.names()) {
    py::list options;
    for (const auto& o : registry.create(name)->options())
      options.append(py::make_tuple(o.name, o.default_value, o.description));
    out[py::str(name)] = options;
  }
  return out;
}

// A matrix of the system must be square and non-empty.
void square_arg(Eigen::Index rows, Eigen::Index cols, const std::string& name) {
  if (rows != cols || rows == 0)
    throw py::value_error(name + ": expected a square matrix with at least one row, got " + std::to_string(rows) +
                          " x " + std::to_string(cols));
}

}  // namespace

void bind_solvers(py::module_& m) {
  m.def(
      "solve",
      [](py::handle data, py::handle indices, py::handle indptr, Eigen::Index rows, Eigen::Index cols, py::handle b,
         const std::string& solver, const py::dict& options, py::handle positions) {
        square_arg(rows, cols, "A");
        Eigen::SparseMatrix<double> A = sparse_in(data, indices, indptr, rows, cols, "A");
        bool was_vector = false;
        const Eigen::MatrixXd B = matrix_arg(b, "b", rows, was_vector);
        auto backend = make_linear_solver(solver, config_arg(options, solver));
        if (!positions.is_none()) backend->set_positions(points_arg(positions, "positions", rows));
        Eigen::MatrixXd X;
        {
          py::gil_scoped_release release;
          backend->compute(std::move(A));
          // No right-hand side, no solution to compute (a backend may refuse an empty B).
          X = B.cols() == 0 ? Eigen::MatrixXd(rows, 0) : backend->solve(B);
        }
        return was_vector ? py::object(to_numpy(Eigen::VectorXd(X.col(0)))) : py::object(to_numpy(X));
      },
      py::arg("data"), py::arg("indices"), py::arg("indptr"), py::arg("rows"), py::arg("cols"), py::arg("b"),
      py::arg("solver"), py::arg("options"), py::arg("positions"));
  m.def(
      "eigs",
      [](py::tuple L, py::tuple M, int k, const std::string& solver, const std::string& eigen_solver,
         const py::dict& options, py::handle positions) {
        auto matrix = [](const py::tuple& t, const char* name) {
          const auto rows = t[3].cast<Eigen::Index>(), cols = t[4].cast<Eigen::Index>();
          square_arg(rows, cols, name);
          return sparse_in(t[0], t[1], t[2], rows, cols, name);
        };
        const Eigen::SparseMatrix<double> Ls = matrix(L, "L"), Ms = matrix(M, "M");
        if (Ls.rows() != Ms.rows())
          throw py::value_error("L, M: different sizes (" + std::to_string(Ls.rows()) + " and " +
                                std::to_string(Ms.rows()) + " rows); pass the L and M of one laplacian call");
        Config config = config_arg(options, eigen_solver);
        // As `corrlap eigs`: the shift-invert linear solver is "solver", cholmod unless named.
        bool takes_solver = false;
        for (const auto& o : eigen_solver_registry().create(eigen_solver)->options())
          takes_solver = takes_solver || o.name == "solver";
        if (!solver.empty()) config.set("solver", solver);
        if (takes_solver && !config.has("solver")) config.set("solver", kDefaultLinearSolver);
        auto backend = make_eigen_solver(eigen_solver, config);
        if (!positions.is_none()) backend->set_positions(points_arg(positions, "positions", Ls.rows()));
        EigenResult r;
        {
          py::gil_scoped_release release;
          r = backend->solve(Ls, Ms, k);
        }
        if (!r.values.allFinite()) throw NumericalError("eigs: the eigen solver returned a value that is not finite");
        return py::make_tuple(to_numpy(r.values), to_numpy(r.vectors), r.method, r.iterations);
      },
      py::arg("L"), py::arg("M"), py::arg("k"), py::arg("solver"), py::arg("eigen_solver"), py::arg("options"),
      py::arg("positions"));
  m.def(
      "backends", [] { return py::make_tuple(describe(linear_solver_registry()), describe(eigen_solver_registry())); },
      "({linear solver: [(option, default, description)]}, {eigen solver: [...]})");
}

}  // namespace corrlap::python

// corrlap eigs: the k smallest values of -lambda for L u = lambda M u (dense solver, small meshes).
#include <Eigen/Dense>
#include <cstdio>
#include <fstream>
#include <iostream>

#include <corrlap/core/error.hpp>

#include "command.hpp"
#include "operator_options.hpp"

namespace corrlap::cli {
namespace {

constexpr Eigen::Index kDenseLimit = 6000;

struct EigsArgs {
  OperatorOptions options;
  int k = 49;
  std::string out;
};

void run(const EigsArgs& a) {
  if (a.k <= 0) throw InputError("-k must be positive");
  const Operators ops = a.options.build();
  const Eigen::Index n = ops.L.rows();
  if (n > kDenseLimit)
    throw InputError("eigs: " + std::to_string(n) + " unknowns is too many for the dense solver (limit " +
                     std::to_string(kDenseLimit) + "); use a sparse eigen solver (--solver, backends issue)");
  // -L u = mu M u with -L positive semi-definite and M symmetric positive definite: mu = -lambda.
  const Eigen::MatrixXd A = -Eigen::MatrixXd(ops.L);
  const Eigen::MatrixXd B = Eigen::MatrixXd(ops.M);
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(A, B, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success)
    throw NumericalError("eigs: the dense generalized eigen solver failed (is M positive definite?)");
  const Eigen::VectorXd mu = es.eigenvalues();  // ascending
  const Eigen::Index k = std::min<Eigen::Index>(a.k, mu.size());
  std::FILE* f = a.out.empty() ? stdout : std::fopen(a.out.c_str(), "w");
  if (!f) throw IoError("cannot write '" + a.out + "'");
  for (Eigen::Index i = 0; i < k; ++i) std::fprintf(f, "%.17g\n", mu[i]);
  if (f != stdout) std::fclose(f);
  if (k < a.k) std::cerr << "eigs: only " << k << " eigenvalues exist\n";
}

RegisterCommand reg(31, "eigs", [](CLI::App& app) {
  auto args = std::make_shared<EigsArgs>();
  auto* cmd = app.add_subcommand("eigs", "smallest eigenvalues -lambda of L u = lambda M u (dense, <= 6000 unknowns)");
  args->options.add_options(*cmd);
  cmd->add_option("-k", args->k, "number of eigenvalues (default 49)");
  cmd->add_option("--out", args->out, "write one value per line (ascending, %.17g) instead of printing");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

// corrlap operators: writes L.mtx and M.mtx (Matrix Market, full precision) of one discretization.
#include <corrlap/io/output_folder.hpp>
#include <corrlap/io/text_io.hpp>
#include <iostream>

#include "command.hpp"
#include "operator_options.hpp"

namespace corrlap::cli {
namespace {

struct OperatorsArgs {
  OperatorOptions options;
  std::string out;
  bool all = false;
};

void run(const OperatorsArgs& a) {
  OutputFolder out(a.out);  // checked before the assembly
  const Operators ops = a.options.build(a.all);
  const std::string dir = out.path() + "/";
  write_matrix_market(dir + "L.mtx", ops.L);
  write_matrix_market(dir + "M.mtx", ops.M);
  std::string written = "L.mtx M.mtx";
  auto extra = [&](const std::optional<Eigen::SparseMatrix<double>>& m, const std::string& name) {
    if (!a.all || !m) return;
    write_matrix_market(dir + name, *m);
    written += " " + name;
  };
  extra(ops.D0, "D0.mtx");
  extra(ops.sharp, "sharp.mtx");
  extra(ops.flat, "flat.mtx");
  extra(ops.M1, "M1.mtx");
  extra(ops.M_lumped, "M_lumped.mtx");
  out.commit();
  std::cerr << a.options.method.method << ": " << ops.L.rows() << " x " << ops.L.cols()
            << ", nnz(L) = " << ops.L.nonZeros() << ", nnz(M) = " << ops.M.nonZeros() << " -> " << a.out << " ("
            << written << ")\n";
}

RegisterCommand reg(30, "operators", [](CLI::App& app) {
  auto args = std::make_shared<OperatorsArgs>();
  auto* cmd = app.add_subcommand("operators", "assemble the stiffness L and mass M of a discretization");
  args->options.add_options(*cmd);
  cmd->add_option("--out", args->out, "output directory (L.mtx, M.mtx)")->required();
  cmd->add_flag("--all", args->all, "also write D0, sharp, flat, M1 and M_lumped when the method has them");
  cmd->callback([args] { run(*args); });
});

}  // namespace
}  // namespace corrlap::cli

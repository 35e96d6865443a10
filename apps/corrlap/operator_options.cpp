#include "operator_options.hpp"

#include <iostream>

#include <corrlap/core/error.hpp>
#include <corrlap/core/threads.hpp>
#include <corrlap/discretizations/registry.hpp>
#include <corrlap/estimators/implicit_normals.hpp>
#include <corrlap/io/text_io.hpp>

namespace corrlap::cli {

void OperatorOptions::add_options(CLI::App& cmd) {
  source.add_options(cmd, /*with_mesh=*/true);
  std::string names;
  for (const auto& n : discretization_registry().names()) names += (names.empty() ? "" : ", ") + n;
  cmd.add_option("--method", method, "discretization: " + names)->required();
  cmd.add_option("--face-normals", face_normals_file, "one unit normal per face (text, nx ny nz, file order)");
  cmd.add_option("--vertex-normals", vertex_normals_file, "one unit normal per vertex (text, nx ny nz, file order)");
  cmd.add_option("--normals", normals,
                 "normals when no file is given: true (implicit shapes; vertex = normalized sum of face "
                 "normals, spec §1.5), trivial (surfel normals), auto (true for shapes)")
      ->check(CLI::IsMember({"auto", "true", "trivial"}));
  cmd.add_option("--lambda", lambda, "stabilization weight (polydec 1, interpolated 0.1)");
  cmd.add_option("--kappa", kappa, "interpolated: flat correction factor (2 = DGtal, 1 = paper)");
  cmd.add_option("--assembly", assembly, "interpolated: global (DGtal L0, default) | local")
      ->check(CLI::IsMember({"global", "local"}));
  cmd.add_option("--mass", mass, "fem: full (default) | lumped; heat-kernel: measure (default) | identity")
      ->check(CLI::IsMember({"full", "lumped", "measure", "identity"}));
  cmd.add_option("--t", heat_t, "heat-kernel: diffusion time (default 0.1 h^(2/3), spec §6)");
  cmd.add_option("--cutoff", cutoff, "heat-kernel: couple points closer than cutoff * sqrt(2t) (default 3)");
  cmd.add_option("--orientation", orientation, "normals with u.n <= 0: error | warn (default) | clamp")
      ->check(CLI::IsMember({"error", "warn", "clamp"}));
  cmd.add_option("--param", params, "method parameter key=value (repeatable)");
  cmd.add_option("--config", config_file, "JSON object of method parameters");
  cmd.add_option("--threads", threads, "worker threads (default: all; env CORRLAP_THREADS)");
}

OperatorOptions::Input OperatorOptions::prepare(bool extras) const {
  if (threads > 0) set_thread_count(threads);
  const auto disc = make_discretization(method);
  Input in;
  in.mesh = source.surface();
  const NormalKind need = disc->required_normals();
  if (!face_normals_file.empty()) in.normals.face = read_normals(face_normals_file);
  if (!vertex_normals_file.empty()) in.normals.vertex = read_normals(vertex_normals_file);
  const bool have_files = in.normals.has_face() || in.normals.has_vertex();
  if (need != NormalKind::None) {
    std::string kind = normals;
    const auto shape = source.implicit_shape();
    if (kind == "auto") kind = have_files ? "" : (shape ? "true" : "");
    if (kind == "true") {
      if (!shape) throw InputError("--normals true needs an implicit shape (--shape or --polynomial)");
      if (!in.normals.has_face()) in.normals.face = true_face_normals(*shape, in.mesh);
    } else if (kind == "trivial") {
      if (!in.normals.has_face()) in.normals.face = in.mesh.face_normals_from_positions();
    }
    if (need == NormalKind::Vertex && !in.normals.has_vertex() && in.normals.has_face()) {
      // spec §1.5: the reference builds vertex normals as the normalized sum of face normals.
      if (in.normals.face.rows() != in.mesh.num_faces())
        throw InputError("face normals: " + std::to_string(in.normals.face.rows()) + " rows for " +
                         std::to_string(in.mesh.num_faces()) + " faces");
      in.normals.vertex = vertex_normals_from_face_normals(in.normals.face, in.mesh.faces, in.mesh.num_vertices());
    }
    if (need == NormalKind::Face && !in.normals.has_face())
      throw InputError(method + " needs face normals: give --face-normals FILE or --normals true|trivial");
    if (need == NormalKind::Vertex && !in.normals.has_vertex())
      throw InputError(method + " needs vertex normals: give --vertex-normals FILE, --face-normals FILE or --normals true|trivial");
  }
  if (!config_file.empty()) in.params = Config::from_json_file(config_file);
  in.params.merge(Config::from_key_values(params));
  if (lambda) in.params.set("lambda", *lambda);
  if (kappa) in.params.set("kappa", *kappa);
  if (heat_t) in.params.set("t", *heat_t);
  if (cutoff) in.params.set("cutoff", *cutoff);
  if (!assembly.empty()) in.params.set("assembly", assembly);
  if (!mass.empty()) in.params.set("mass", mass);
  if (!orientation.empty()) in.params.set("orientation", orientation);
  if (extras) {
    bool supported = false;
    for (const auto& p : disc->parameters()) supported = supported || p.name == "extras";
    if (supported) in.params.set("extras", true);
    else std::cerr << "warning: " << method << " has no extra operators (D0, sharp, flat, M1)\n";
  }
  return in;
}

Operators OperatorOptions::build(bool extras) const {
  const Input in = prepare(extras);
  Operators ops = make_discretization(method)->assemble(in.mesh, in.normals, in.params);
  for (const auto& w : ops.warnings) std::cerr << "warning: " << w << "\n";
  return ops;
}

}  // namespace corrlap::cli

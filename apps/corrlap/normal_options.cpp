#include "normal_options.hpp"

#include <iostream>

#include "library_errors.hpp"
#include "validators.hpp"

namespace corrlap::cli {

ProgressFn stderr_progress(const std::string& what) {
  // Short runs stay quiet.
  return tenths_progress(
      what, [](const std::string& line) { std::cerr << line << "\n"; }, 20000);
}

void NormalOptions::add_options(CLI::App& cmd) {
  cmd.add_option("--face-normals", face_file, "one unit normal per face (text, nx ny nz, file order)");
  cmd.add_option("--vertex-normals", vertex_file, "one unit normal per vertex (text, nx ny nz, file order)");
  source_option =
      cmd.add_option(
             "--normals", source,
             "normals when no file gives them: true (implicit shapes), ii (integral invariant of the voxels, "
             "docs/math.md §7), trivial (surfel normals), convolved (surfel normals averaged over a 3-voxel "
             "neighbourhood), auto (true for shapes, ii for volumes); vertex normals are the normalized sum of the "
             "face normals (docs/math.md §1.5)")
          ->check(CLI::IsMember({"auto", "true", "ii", "trivial", "convolved"}))
          ->capture_default_str();
  const IIParams voxels = default_ii_params(/*implicit_shape=*/false), shapes = default_ii_params(true);
  cmd.add_option("--ii-radius", ii_k,
                 "II: radius factor k, Euclidean radius k*h^alpha; default: for volumes and mesh files " +
                     number_text(voxels.k) + " with --ii-alpha " + number_text(voxels.alpha) + ", i.e. " +
                     number_text(voxels.k) +
                     " voxels (docs/regularization.md, \"Default radii\"); for --shape and --polynomial the paper's " +
                     number_text(shapes.k) + " with --ii-alpha " + number_text(shapes.alpha))
      ->check(positive_number());
  cmd.add_option("--ii-alpha", ii_alpha,
                 "II: exponent alpha (default " + number_text(voxels.alpha) + " for volumes and mesh files, " +
                     number_text(shapes.alpha) + " for shapes)");
  cmd.add_option("--ii-thin-parts", ii_thin_parts,
                 "II: shrink: where the ball reaches across a part thinner than itself (a rod, a thin wall, a "
                 "speck), estimate those surfels again with smaller balls (docs/math.md §7.2); keep: the radius "
                 "everywhere, as DGtal (default: shrink for volumes and mesh files, keep for --shape and --polynomial)")
      ->check(CLI::IsMember({"shrink", "keep"}));
}

NormalRequest NormalOptions::request(bool implicit_shape) const {
  NormalRequest r;
  r.source = parse_normal_source(source);
  r.face_normals_file = face_file;
  r.vertex_normals_file = vertex_file;
  std::optional<bool> shrink;
  if (!ii_thin_parts.empty()) shrink = ii_thin_parts == "shrink";
  r.ii = default_ii_params(implicit_shape, ii_k, ii_alpha, shrink);
  r.progress = stderr_progress("ii normals");
  return r;
}

NormalFields NormalOptions::resolve(const LoadedSurface& s, NormalKind need, const std::string& what) const {
  return in_cli_terms([&] { return resolve_normals(s, need, request(s), what); });
}

std::string NormalOptions::describe(const LoadedSurface& s) const {
  if (!face_file.empty() || !vertex_file.empty()) return "file";
  return to_string(effective_normal_source(parse_normal_source(source), s.shape_ptr(), s.grid_ptr()));
}

}  // namespace corrlap::cli

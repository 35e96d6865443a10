#include "surface_source.hpp"

#include <algorithm>
#include <cctype>
#include <corrlap/core/error.hpp>
#include <iostream>

#include "library_errors.hpp"
#include "validators.hpp"

namespace corrlap::cli {

void SurfaceSource::add_options(CLI::App& cmd, bool with_mesh) {
  allow_mesh = with_mesh;
  auto* g = cmd.add_option_group("surface", "where the digital surface comes from (one of)");
  auto* s = g->add_option("--shape", shape, "named implicit shape (sphere1, torus, goursat, ...)");
  auto* p = g->add_option("--polynomial", polynomial, "implicit shape P(x,y,z) <= 0, e.g. \"x^2+y^2+z^2-1\"");
  auto* v =
      g->add_option("--volume", volume,
                    "volume file (docs/io.md: .nii/.nii.gz, .nrrd, .mha/.mhd, .vol, .longvol, .raw, .binvox, .vox, "
                    ".npy, .tif): inside = every nonzero voxel, or --label N, --labels all, --threshold T");
  auto* mf = g->add_option("--mesh-file", mesh_file,
                           "closed triangle mesh (.obj, .ply, .off) voxelized at --resolution N or grid step --h");
  CLI::Option* m = nullptr;
  if (with_mesh) m = g->add_option("--mesh", mesh, "quad mesh of surfels (.obj), vertex/face order kept");
  g->require_option(1);
  (void)s;
  (void)p;
  (void)v;
  (void)m;
  (void)mf;
  h_option = cmd.add_option("--h", h,
                            "grid step (shapes: world units per voxel; volumes: voxel size, default 2/N so that the "
                            "longest side (N voxels) spans 2; mesh files: voxel size in mesh units)")
                 ->check(positive_number());
  cmd.add_option("--resolution", resolution, "mesh files: longest bounding-box side = N voxels")
      ->check(positive_number());
  cmd.add_option("--center", center, "shape centre X Y Z")->expected(3);
  cmd.add_option("--bbox", bbox, "digitization box MIN MAX (reference default -10 10)")->expected(2);
  cmd.add_option("--offset", offset, "extra voxels around the box (reference default 5)")->check(non_negative_number());
  auto* t =
      cmd.add_option("--threshold", threshold, "volumes: a voxel is inside when its value > T (grey-level images)");
  auto* l =
      cmd.add_option("--label", label, "volumes: a voxel is inside when its value == N (one label of a segmentation)");
  labels_option = cmd.add_option("--labels", labels,
                                 "volumes: all: one surface per distinct nonzero value, each in its own output "
                                 "(regularize: OUT/label-N/)")
                      ->check(CLI::IsMember({"all"}));
  t->excludes(l)->excludes(labels_option);
  l->excludes(labels_option);
  cmd.add_option("--raw-dimensions", raw_dimensions, "raw volumes: NX NY NZ")->expected(3);
}

SurfaceInput SurfaceSource::input() const {
  const bool h_given = h_option && h_option->count() > 0;
  if (resolution > 0 && mesh_file.empty()) throw InputError("--resolution applies to --mesh-file only");
  if (volume.empty() && (threshold || label || !labels.empty()))
    throw InputError(std::string(threshold ? "--threshold"
                                 : label   ? "--label"
                                           : "--labels") +
                     " applies to --volume only");
  if (!shape.empty() || !polynomial.empty()) {
    ImplicitShapeInput in;
    in.shape = !shape.empty() ? shape : polynomial;
    in.center = Eigen::Vector3d(center[0], center[1], center[2]);
    in.digitization.h = h;
    in.digitization.min_aabb = bbox[0];
    in.digitization.max_aabb = bbox[1];
    in.digitization.offset = offset;
    return in;
  }
  if (!volume.empty()) {
    if (all_labels())
      throw InputError("--labels all gives one surface per label: the command writes one output only (give --label N)");
    VolumeFileInput in;
    in.path = volume;
    in.inside = inside();
    if (h_given) in.h = h;  // else world units (docs/io.md): the longest side spans 2
    if (raw_dimensions.size() == 3)
      in.raw_dimensions = Eigen::Vector3i(raw_dimensions[0], raw_dimensions[1], raw_dimensions[2]);
    return in;
  }
  if (!mesh_file.empty()) {
    if (resolution > 0 && h_given) throw InputError("--mesh-file: give either --resolution or --h, not both");
    if (resolution <= 0 && !h_given)
      throw InputError("--mesh-file needs --resolution N (voxels along the longest side) or --h STEP");
    MeshFileInput in;
    in.path = mesh_file;
    in.resolution = resolution;
    if (h_given) in.h = h;
    return in;
  }
  if (!mesh.empty()) {
    QuadMeshInput in;
    in.path = mesh;
    return in;
  }
  throw InputError("no surface source: give --shape, --polynomial, --volume, --mesh-file or --mesh");
}

LoadedSurface SurfaceSource::load() const {
  const SurfaceInput in = input();
  LoadMessages messages;
  messages.warning = [](const std::string& w) { std::cerr << "warning: " << w << "\n"; };
  messages.note = [](const std::string& n) { std::cerr << n << "\n"; };
  return in_cli_terms([&] { return load_surface(in, messages); });
}

InsideRule SurfaceSource::inside() const {
  if (threshold) return InsideRule::above(*threshold);
  if (label) return InsideRule::label(*label);
  return InsideRule::nonzero();
}

OutputUnits OutputUnits::parse(const std::string& name, const VoxelFrame& frame, const std::string& space) {
  OutputUnits u;
  u.frame = frame;
  if (name == "physical")
    u.kind = Kind::Physical;
  else if (name == "world")
    u.kind = Kind::World;
  else if (name == "voxels")
    u.kind = Kind::Voxels;
  else
    throw InputError("--output-units '" + name + "': expected physical, world or voxels", "output_units");
  if (u.kind != Kind::World && !(u.frame.h() > 0.0))
    throw InputError("--output-units " + name + ": the surface has no grid step", "output_units");
  std::string wanted = space;
  std::transform(wanted.begin(), wanted.end(), wanted.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (wanted == "file") {
    u.space = frame.space();
    return u;
  }
  if (wanted != "ras" && wanted != "lps")
    throw InputError("--output-space '" + space + "': expected file, ras or lps", "output_space");
  if (u.kind != Kind::Physical)
    throw InputError("--output-space " + space + " applies to --output-units physical (" + name +
                         " coordinates have no anatomical space)",
                     "output_space");
  u.space = wanted == "ras" ? PhysicalSpace::RAS : PhysicalSpace::LPS;
  try {
    u.flip = frame.space_change_to(u.space);
  } catch (const InputError& e) {
    throw InputError(
        "--output-space " + space + ": " + e.what() + "; omit --output-space to write the input's own coordinates",
        "output_space");
  }
  return u;
}

const char* OutputUnits::name() const {
  switch (kind) {
    case Kind::Physical:
      return "physical";
    case Kind::World:
      return "world";
    case Kind::Voxels:
      return "voxels";
  }
  return "physical";
}

std::vector<std::string> OutputUnits::scalar_comments(const std::string& what, int power) const {
  std::string line =
      what + " in 1/length" + (power == 1 ? std::string() : "^" + std::to_string(power)) + " of " + name() + " units";
  if (kind == Kind::Physical && space != PhysicalSpace::Unknown) line += " (SPACE=" + corrlap::space_name(space) + ")";
  return {line};
}

std::string OutputUnits::space_name() const { return kind == Kind::Physical ? corrlap::space_name(space) : ""; }

std::vector<std::string> OutputUnits::comments() const {
  if (kind != Kind::Physical || space == PhysicalSpace::Unknown) return {};
  return {"SPACE=" + corrlap::space_name(space)};
}

double OutputUnits::length_scale() const {
  switch (kind) {
    case Kind::Physical:
      return frame.length_to_physical(1.0);
    case Kind::World:
      return 1.0;
    case Kind::Voxels:
      return frame.length_to_index(1.0);
  }
  return 1.0;
}

SurfelMesh OutputUnits::mesh(const SurfelMesh& m) const {
  if (kind == Kind::World) return m;
  SurfelMesh out = m;
  out.positions = kind == Kind::Voxels ? frame.to_index(m.positions) : frame.to_physical(m.positions) * flip;
  if (out.h > 0) out.h = m.h * length_scale();
  if (mirrors()) out.faces = out.faces.rowwise().reverse().eval();
  return out;
}

bool OutputUnits::mirrors() const {
  // flip is diagonal (its own transpose); it mirrors when it flips one axis (RAS <-> LAS).
  return kind == Kind::Physical && frame.mirrors() != (flip.determinant() < 0.0);
}

namespace {

// False when physical vectors are the world ones: the voxel axes are the physical axes (cubic
// voxels scale lengths only) and no space flip; the unit vectors are then kept bit for bit.
bool turns_vectors(const OutputUnits& u) {
  return u.kind == OutputUnits::Kind::Physical &&
         ((u.frame.geometry() && u.frame.geometry()->direction != Eigen::Matrix3d::Identity()) ||
          u.flip != Eigen::Matrix3d::Identity());
}

}  // namespace

Eigen::MatrixX3d OutputUnits::normals(const Eigen::MatrixX3d& n) const {
  return turns_vectors(*this) ? Eigen::MatrixX3d(frame.normals_to_physical(n) * flip) : n;
}

Eigen::MatrixX3d OutputUnits::directions(const Eigen::MatrixX3d& d) const {
  if (!turns_vectors(*this)) return d;
  // Tangent vectors follow the linear part of the map (normals its inverse transpose); the
  // resampled voxels are cubes, so the direction matrix alone is that part up to scale.
  const Eigen::Matrix3d direction = frame.geometry() ? frame.geometry()->direction : Eigen::Matrix3d::Identity();
  Eigen::MatrixX3d out = d * direction.transpose() * flip;
  for (Eigen::Index i = 0; i < out.rows(); ++i) {
    const double norm = out.row(i).norm();
    if (norm > 0.0) out.row(i) /= norm;
  }
  return out;
}

void OutputOptions::add_options(CLI::App& cmd, bool with_space) {
  cmd.add_option("--output-units", units, OutputUnits::kHelp)
      ->check(CLI::IsMember({"physical", "world", "voxels"}))
      ->capture_default_str();
  if (with_space)
    cmd.add_option("--output-space", space, OutputUnits::kSpaceHelp)
        ->check(CLI::IsMember({"file", "ras", "lps"}, CLI::ignore_case))
        ->capture_default_str();
}

std::string SurfaceSource::describe() const { return corrlap::describe(input()); }

void check_regularizable(const SurfelMesh& mesh, const std::string& command) {
  in_cli_terms([&] { corrlap::check_regularizable(mesh); }, command);
}

}  // namespace corrlap::cli

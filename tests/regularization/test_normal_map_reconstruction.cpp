// Reconstruction from a normal map (paper §4.2, regularization/normal_map_reconstruction.hpp,
// `corrlap reconstruct`): the quad subdivision keeps a closed surface closed and oriented, the
// sampled normals are the fine mesh's, and the regularization moves the staircase onto the mesh.
#include <doctest/doctest.h>

#include <corrlap/corrlap.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "surface/icosahedron.hpp"
#include "test_support.hpp"

using namespace corrlap;

namespace {
// The icosahedron refined to ~10k vertices and pushed onto the unit sphere.
PolygonMesh fine_sphere() {
  TriangleMesh t = test::icosahedron();
  loop_refine(t, 10000);
  PolygonMesh m;
  m.positions = t.positions.rowwise().normalized();
  for (Eigen::Index i = 0; i < t.triangles.rows(); ++i)
    m.faces.push_back({t.triangles(i, 0), t.triangles(i, 1), t.triangles(i, 2)});
  return m;
}
}  // namespace

TEST_CASE("subdivide_quads: s^2 quads per surfel, shared edge points, closed, oriented, same area") {
  const SurfelMesh coarse =
      extract_surface(digitize(make_implicit_shape("sphere1"), {.h = 0.25, .min_aabb = -1.5, .max_aabb = 1.5}));
  const EdgeTopology edges = build_edges(coarse);
  for (int levels : {1, 2}) {
    CAPTURE(levels);
    const int s = 1 << levels;
    const SurfelMesh fine = subdivide_quads(coarse, levels);
    CHECK(fine.num_faces() == coarse.num_faces() * s * s);
    CHECK(fine.num_vertices() ==
          coarse.num_vertices() + edges.num_edges() * (s - 1) + coarse.num_faces() * (s - 1) * (s - 1));
    CHECK(fine.grid_step() == doctest::Approx(coarse.grid_step() / s));
    const MeshInfo info = compute_mesh_info(fine);
    CHECK(info.closed());
    CHECK(info.manifold());
    CHECK(info.euler == compute_mesh_info(coarse).euler);
    CHECK(info.isolated_vertices == 0);
    CHECK(surface_area(fine) == doctest::Approx(surface_area(coarse)).epsilon(1e-12));
    // Each child keeps its parent's (outward) normal.
    const Eigen::MatrixX3d parent = coarse.face_normals_from_positions(), child = fine.face_normals_from_positions();
    double worst = 0;
    for (int f = 0; f < fine.num_faces(); ++f) worst = std::max(worst, (child.row(f) - parent.row(f / (s * s))).norm());
    CHECK(worst < 1e-12);
  }
  CHECK(subdivide_quads(coarse, 0).faces == coarse.faces);
  CHECK_THROWS_AS(subdivide_quads(coarse, 7), InputError);
}

TEST_CASE("normal map on a sphere: sampled normals are radial, regularization moves onto the fine mesh") {
  const PolygonMesh fine = fine_sphere();
  const TriangleIndices T = triangulate(fine);
  const TriangleLocator locator(fine.positions, T);
  const Eigen::MatrixX3d N = triangle_mesh_vertex_normals(fine.positions, T);
  CHECK((N - fine.positions).rowwise().norm().maxCoeff() < 0.01);  // a fine sphere: radial normals
  MeshVoxelizationParams params;
  params.resolution = 16;
  const SurfelMesh mesh = subdivide_quads(extract_surface(voxelize_mesh(fine, params)), 2);
  const NormalFields normals = sample_normal_map(mesh, locator, N);
  // The closest point of p on the unit sphere is p / |p|: the normal there is radial.
  CHECK((normals.vertex - mesh.positions.rowwise().normalized()).rowwise().norm().maxCoeff() < 0.01);
  const DistanceToMesh before = distance_to_mesh(mesh, locator);
  RegularizationOptions o;
  o.curvature_radius = 0.2;
  o.h_clamp = 10.0;
  o.alpha_step = 2.0 / 16;
  const RegularizedSurface r = regularize_surface(mesh, normals, o);
  const DistanceToMesh after = distance_to_mesh(r.mesh, locator);
  MESSAGE("mean distance to the fine sphere " << before.mean << " -> " << after.mean << " (max " << before.max << " -> "
                                              << after.max << ")");
  CHECK(after.mean < 0.3 * before.mean);
  // The shading: the subdivided staircase's vertex normals are tens of degrees off the map (most are
  // axis-aligned), the regularized surface's about one.
  const double angle_before = normal_angle_to_map(mesh, locator, N),
               angle_after = normal_angle_to_map(r.mesh, locator, N);
  MESSAGE("mean normal angle to the map " << angle_before << " -> " << angle_after << " degrees");
  CHECK(angle_before > 10.0);
  CHECK(angle_after < 0.25 * angle_before);
  // On the fine sphere itself the angle is that of its own facets' normals against the map's.
  SurfelMesh on_sphere = mesh;
  on_sphere.positions = mesh.positions.rowwise().normalized();
  CHECK(normal_angle_to_map(on_sphere, locator, N) < 0.5);  // measured 0.1
  CHECK_THROWS_AS(sample_normal_map(mesh, locator, N.topRows(5)), InputError);
  CHECK_THROWS_AS(normal_angle_to_map(mesh, locator, N.topRows(5)), InputError);
}

TEST_CASE("corrlap reconstruct: files, metrics, the corrected method closer than the staircase") {
  const std::string dir = test::tmp_path("reconstruct");
  std::filesystem::remove_all(dir);
  const std::string obj = test::tmp_path("reconstruct_sphere.obj");
  write_mesh(obj, fine_sphere());
  std::string out, err;
  REQUIRE(test::run_cli("reconstruct --mesh-file " + obj + " --resolution 16 --subdivide 2 --out " + dir, &out, &err) ==
          0);
  for (const char* f : {"input.ply", "reconstructed_fem.ply", "reconstructed_polydec.ply", "metrics.json", "fine.png",
                        "before.png", "after_fem.png", "after_polydec.png"})
    CHECK_MESSAGE(std::filesystem::exists(dir + "/" + f), f);
  const auto m = nlohmann::json::parse(test::read_text(dir + "/metrics.json"));
  const double before = m["distance_mean_before"], fem = m["methods"]["fem"]["distance_mean_after"];
  CHECK(fem < 0.3 * before);
  CHECK(m["subdivide"] == 2);
  CHECK(m["h_clamp"].get<double>() > 0);
  // The default radius is in coarse voxels (the normals come from the map, not from the staircase).
  CHECK(m["curvature_radius"].get<double>() ==
        doctest::Approx(kReconstructionCurvatureRadiusVoxels * m["h"].get<double>()));
  const double angle_before = m["normal_angle_before_deg"], angle_fem = m["methods"]["fem"]["normal_angle_after_deg"];
  MESSAGE("normal angle to the map " << angle_before << " -> " << angle_fem << " (fem), "
                                     << m["methods"]["polydec"]["normal_angle_after_deg"].get<double>()
                                     << " (polydec)");
  CHECK(angle_fem < 0.25 * angle_before);
  CHECK(test::run_cli("reconstruct --mesh-file " + obj + " --methods nosuch --out " + dir, &out, &err) == 1);
  CHECK(test::run_cli("reconstruct --mesh-file " + dir + "/missing.obj --out " + dir, &out, &err) == 1);
}

TEST_CASE("corrlap reconstruct: a coarse voxelization whose voxels touch along an edge is split and runs") {
  // Two unit cubes that share one edge (x = y = 1): their voxels touch along it at any resolution.
  std::string obj_text;
  const int quads[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
  for (const int offset : {0, 1})
    for (int corner = 0; corner < 8; ++corner)
      obj_text += "v " + std::to_string(offset + corner / 4) + " " + std::to_string(offset + corner / 2 % 2) + " " +
                  std::to_string(corner % 2) + "\n";
  for (const int base : {1, 9})
    for (const auto& q : quads)
      obj_text += "f " + std::to_string(base + q[0]) + " " + std::to_string(base + q[1]) + " " +
                  std::to_string(base + q[2]) + " " + std::to_string(base + q[3]) + "\n";
  const std::string obj = test::tmp_path("two_cubes.obj");
  test::write_text(obj, obj_text);
  const std::string dir = test::tmp_path("reconstruct_nonmanifold");
  std::string out, err;
  CHECK(test::run_cli("reconstruct --mesh-file " + obj + " --resolution 8 --subdivide 1 --no-render --out " + dir, &out,
                      &err) == 0);
  const auto m = nlohmann::json::parse(test::read_text(dir + "/metrics.json"));
  CHECK(std::isfinite(m["methods"]["fem"]["distance_mean_after"].get<double>()));
  // The flag that let such voxelizations through is still accepted.
  CHECK(test::run_cli("reconstruct --mesh-file " + obj +
                          " --resolution 8 --subdivide 1 --no-render --allow-nonmanifold --out " + dir,
                      &out, &err) == 0);
}

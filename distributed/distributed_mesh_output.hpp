#pragma once
// Mesh files of the distributed front end written without gathering the surface (docs/distributed.md,
// "Writing the outputs"): each rank writes its owned vertices and faces at their serial places in
// one file (MPI-IO), rank 0 the header. No rank holds the whole mesh, and the file is byte for byte
// the one write_mesh writes for the gathered mesh.
#include <Eigen/Core>
#include <corrlap/io/mesh_io.hpp>
#include <string>
#include <vector>

#include "distributed_surface.hpp"

namespace corrlap {

/// Rows at the local vertices (#Vl by k): the owned rows as given (#owned by k), the others'
/// fetched from the ranks that own them. Collective.
Eigen::MatrixXd local_rows(const DistributedSurface& s, const Eigen::MatrixXd& owned);

/// Sums at the owned vertices (#owned by k) of rows given at the local vertices (#Vl by k): a
/// vertex's own row plus the rows other ranks hold for it. Collective.
Eigen::MatrixXd sum_at_owners(const DistributedSurface& s, const Eigen::MatrixXd& local);

/// geometric_vertex_normals (regularization/surface_quality.hpp) of the surface whose owned
/// vertices are at `positions` (#owned by 3), at the owned vertices: the normalized sums of the
/// normals of the faces around them. Equal to the serial ones up to the order of the sums.
/// Collective.
Eigen::MatrixX3d distributed_geometric_vertex_normals(const DistributedSurface& s, const Eigen::MatrixX3d& positions);

/// write_mesh(path, mesh, attributes) for the whole surface with its owned vertices at
/// `positions` (#owned by 3) and `attributes`' vertex normals and scalars at the owned vertices
/// (#owned rows; no face attributes), written by every rank into one file. `path` must be the same
/// on every rank and on a file system they all see. The file appears whole or not at all: IoError
/// on every rank when any rank's part fails (a non-finite value) or the file cannot be written.
/// Collective.
/// `reverse_faces`: each face's corners in reverse order (a mirroring map of the positions).
void write_distributed_mesh(const std::string& path, const DistributedSurface& s, const Eigen::MatrixX3d& positions,
                            const MeshAttributes& attributes, bool reverse_faces = false);

/// write_scalars(path, values, comments) of one value per vertex of the whole surface, in serial
/// vertex order, from `values` at the owned vertices (#owned), written by every rank into one file
/// as write_distributed_mesh writes. Collective.
void write_distributed_scalars(const std::string& path, const DistributedSurface& s, const Eigen::VectorXd& values,
                               const std::vector<std::string>& comments = {});

}  // namespace corrlap

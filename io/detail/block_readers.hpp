#pragma once
// The block-streaming readers with their block size as a parameter (internal): the public
// read_ply / read_off / read_matrix_market use LineReader::kDefaultBlock; tests pass a few bytes so
// that records, lines and numbers straddle block boundaries.
#include <Eigen/Sparse>
#include <corrlap/io/mesh_io.hpp>
#include <cstddef>
#include <string>

namespace corrlap::io_detail {

PolygonMesh read_ply(const std::string& path, MeshAttributes* attributes, std::size_t block_bytes);
PolygonMesh read_off(const std::string& path, std::size_t block_bytes);
Eigen::SparseMatrix<double> read_matrix_market(const std::string& path, std::size_t block_bytes);

}  // namespace corrlap::io_detail

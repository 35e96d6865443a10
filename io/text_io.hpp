#pragma once
// Plain-text fields (one row of numbers per line) and Matrix Market matrices.
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <cstdint>
#include <string>
#include <vector>

namespace corrlap {

/// Reads "nx ny nz" per line (blank lines and # comments skipped). Throws IoError naming the
/// file and line for malformed or non-finite values, a wrong column count, or an empty file.
Eigen::MatrixX3d read_normals(const std::string& path);
/// Writes one "nx ny nz" line per row with 17 significant digits.
void write_normals(const std::string& path, const Eigen::MatrixX3d& normals);

/// One value per line (same rules as read_normals).
Eigen::VectorXd read_scalars(const std::string& path);
/// One value per line with 17 significant digits, after one "# " line per comment (what the values
/// are, their units: read_scalars, numpy.loadtxt and most readers skip them).
void write_scalars(const std::string& path, const Eigen::VectorXd& values,
                   const std::vector<std::string>& comments = {});

/// write_scalars' file in pieces, for writers that hold some of the rows (distributed/): its
/// comment lines, and the lines of rows first + 1, first + 2, ... (1-based in errors). The comment
/// lines followed by every piece's lines in row order are write_scalars' file, byte for byte.
/// IoError naming the row on a non-finite value.
std::string scalars_file_header(const std::vector<std::string>& comments);
std::string scalars_file_rows(const std::string& path, const Eigen::VectorXd& values, std::int64_t first);

/// "%%MatrixMarket matrix coordinate real general", 1-based, every stored entry, %.17g.
void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& A);
/// Reads coordinate real general/symmetric files (symmetric ones are expanded).
Eigen::SparseMatrix<double> read_matrix_market(const std::string& path);

}  // namespace corrlap

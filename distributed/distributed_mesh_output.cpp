#include "distributed_mesh_output.hpp"

#include <mpi.h>

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <corrlap/io/mesh_parts.hpp>
#include <corrlap/io/text_io.hpp>
#include <cstdint>
#include <filesystem>
#include <numeric>
#include <optional>
#include <vector>

#include "detail/exchange.hpp"

namespace corrlap {

namespace {

using detail::all_to_all;

// The rank that owns each row: the first rows of every rank, gathered.
class RowOwners {
 public:
  explicit RowOwners(const DistributedSurface& s) : begins_(std::size_t(s.ranks)) {
    MPI_Allgather(&s.row_begin, 1, MPI_INT64_T, begins_.data(), 1, MPI_INT64_T, MPI_COMM_WORLD);
  }
  int owner(std::int64_t row) const {
    return int(std::upper_bound(begins_.begin(), begins_.end(), row) - begins_.begin()) - 1;
  }
  std::int64_t begin(int rank) const { return begins_[std::size_t(rank)]; }

 private:
  std::vector<std::int64_t> begins_;
};

// The same IoError on every rank when any rank failed (the lowest failing rank's message).
void rethrow_everywhere(const std::optional<std::string>& failure) {
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  int first = failure ? rank : ranks;
  MPI_Allreduce(MPI_IN_PLACE, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == ranks) return;
  std::string message = failure && rank == first ? *failure : std::string();
  int length = int(message.size());
  MPI_Bcast(&length, 1, MPI_INT, first, MPI_COMM_WORLD);
  message.resize(std::size_t(length));
  MPI_Bcast(message.data(), length, MPI_CHAR, first, MPI_COMM_WORLD);
  throw IoError(message);
}

// A run of consecutive serial ids: local items begin .. begin + count - 1 have ids first ...
struct Run {
  std::int64_t first = 0;
  Eigen::Index begin = 0, count = 0;
};

// The runs of `ids` (increasing).
std::vector<Run> runs_of(const std::vector<std::int64_t>& ids, Eigen::Index n) {
  std::vector<Run> runs;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!runs.empty() && ids[std::size_t(i)] == runs.back().first + runs.back().count &&
        runs.back().begin + runs.back().count == i)
      ++runs.back().count;
    else
      runs.push_back({ids[std::size_t(i)], i, 1});
  }
  return runs;
}

// MPI-IO takes int counts: large blocks go in pieces.
bool write_at(MPI_File file, std::int64_t offset, const std::string& bytes) {
  constexpr std::size_t kPiece = std::size_t(1) << 30;
  for (std::size_t done = 0; done < bytes.size(); done += kPiece) {
    const int n = int(std::min(kPiece, bytes.size() - done));
    if (MPI_File_write_at(file, MPI_Offset(offset + std::int64_t(done)), bytes.data() + done, n, MPI_BYTE,
                          MPI_STATUS_IGNORE) != MPI_SUCCESS)
      return false;
  }
  return true;
}

// Writes `header` (rank 0's) and every rank's `blocks` into one file at `path`: block b has the keys
// (section, first id, bytes) at 3 b in `keys`; the file is the header, then the blocks in the
// order of their keys over all ranks. Written into a temporary name beside the file and renamed by
// rank 0 once every rank has written. Collective.
void write_runs(const std::string& path, const DistributedSurface& s, const std::string& header,
                const std::vector<std::int64_t>& keys, const std::vector<std::string>& blocks) {
  // Every block's place: after the header, in the order of the keys.
  std::vector<int> counts;
  const std::vector<std::int64_t> all = detail::gather_everywhere(keys, counts);
  std::vector<std::size_t> order(all.size() / 3);
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::make_pair(all[3 * a], all[3 * a + 1]) < std::make_pair(all[3 * b], all[3 * b + 1]);
  });
  std::vector<std::int64_t> offset_of(order.size());  // by index into `all`
  std::int64_t at = std::int64_t(header.size());
  for (std::size_t i : order) {
    offset_of[i] = at;
    at += all[3 * i + 2];
  }
  const std::int64_t mine = std::accumulate(counts.begin(), counts.begin() + s.rank, 0) / 3;

  // Written into a temporary name beside the file, renamed by rank 0 once every rank has closed it.
  const std::string temporary = path + ".partial";
  MPI_File file;
  const bool opened = MPI_File_open(MPI_COMM_WORLD, temporary.c_str(), MPI_MODE_CREATE | MPI_MODE_WRONLY, MPI_INFO_NULL,
                                    &file) == MPI_SUCCESS;
  int ok = opened ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &ok, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (!ok) {
    if (opened) MPI_File_close(&file);
    throw IoError("output file '" + path + "': cannot create '" + temporary + "' on every rank");
  }
  int written = MPI_File_set_size(file, MPI_Offset(at)) == MPI_SUCCESS ? 1 : 0;
  if (s.rank == 0) written = written && write_at(file, 0, header);
  for (std::size_t b = 0; b < blocks.size(); ++b)
    written = written && write_at(file, offset_of[std::size_t(mine) + b], blocks[b]);
  written = (MPI_File_close(&file) == MPI_SUCCESS) && written;
  MPI_Allreduce(MPI_IN_PLACE, &written, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  std::error_code error;
  if (written && s.rank == 0) std::filesystem::rename(temporary, path, error);
  if (!written && s.rank == 0) std::filesystem::remove(temporary, error);
  int renamed = written && !error ? 1 : 0;
  MPI_Bcast(&renamed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (!renamed)
    throw IoError("output file '" + path + "': " +
                  (written ? "cannot rename '" + temporary + "' to it: " + error.message()
                           : std::string("a rank could not write its part")));
}

}  // namespace

Eigen::MatrixXd local_rows(const DistributedSurface& s, const Eigen::MatrixXd& owned) {
  const Eigen::Index nl = s.mesh.num_vertices(), k = owned.cols();
  if (owned.rows() != s.num_owned) throw InputError("local_rows: expected one row per owned vertex");
  const RowOwners owners(s);
  // Ask each owner for the rows of this rank's other vertices.
  std::vector<std::vector<std::int64_t>> asks(std::size_t(s.ranks));
  std::vector<std::vector<Eigen::Index>> asked_by(std::size_t(s.ranks));  // the local vertex of each ask
  for (Eigen::Index v = s.num_owned; v < nl; ++v) {
    const auto r = std::size_t(owners.owner(s.rows[std::size_t(v)]));
    asks[r].push_back(s.rows[std::size_t(v)]);
    asked_by[r].push_back(v);
  }
  std::vector<Eigen::Index> asked_for;  // in send order: owner after owner
  for (const auto& vertices : asked_by) asked_for.insert(asked_for.end(), vertices.begin(), vertices.end());
  std::vector<int> ask_counts(std::size_t(s.ranks)), asked_counts;
  for (int r = 0; r < s.ranks; ++r) ask_counts[std::size_t(r)] = int(asks[std::size_t(r)].size());
  const std::vector<std::int64_t> asked = all_to_all(asks, asked_counts);
  std::vector<double> answers(asked.size() * std::size_t(k));
  for (std::size_t i = 0; i < asked.size(); ++i)
    for (Eigen::Index c = 0; c < k; ++c)
      answers[i * std::size_t(k) + std::size_t(c)] = owned(asked[i] - s.row_begin, c);
  std::vector<int> answer_counts(asked_counts), reply_counts(ask_counts);
  for (int& c : answer_counts) c *= int(k);
  for (int& c : reply_counts) c *= int(k);
  const std::vector<double> replies = all_to_all(answers, answer_counts, reply_counts);
  Eigen::MatrixXd local(nl, k);
  local.topRows(s.num_owned) = owned;
  for (std::size_t i = 0; i < asked_for.size(); ++i)
    for (Eigen::Index c = 0; c < k; ++c) local(asked_for[i], c) = replies[i * std::size_t(k) + std::size_t(c)];
  return local;
}

Eigen::MatrixXd sum_at_owners(const DistributedSurface& s, const Eigen::MatrixXd& local) {
  const Eigen::Index nl = s.mesh.num_vertices(), k = local.cols();
  if (local.rows() != nl) throw InputError("sum_at_owners: expected one row per local vertex");
  const RowOwners owners(s);
  std::vector<std::vector<std::int64_t>> rows(std::size_t(s.ranks));
  std::vector<std::vector<double>> values(std::size_t(s.ranks));
  for (Eigen::Index v = s.num_owned; v < nl; ++v) {
    const int r = owners.owner(s.rows[std::size_t(v)]);
    rows[std::size_t(r)].push_back(s.rows[std::size_t(v)]);
    for (Eigen::Index c = 0; c < k; ++c) values[std::size_t(r)].push_back(local(v, c));
  }
  std::vector<int> counts(std::size_t(s.ranks)), from_counts;
  std::vector<double> flat;
  for (int r = 0; r < s.ranks; ++r) {
    counts[std::size_t(r)] = int(values[std::size_t(r)].size());
    flat.insert(flat.end(), values[std::size_t(r)].begin(), values[std::size_t(r)].end());
  }
  const std::vector<std::int64_t> got_rows = all_to_all(rows, from_counts);
  std::vector<int> value_counts(from_counts);
  for (int& c : value_counts) c *= int(k);
  const std::vector<double> got = all_to_all(flat, counts, value_counts);
  Eigen::MatrixXd sums = local.topRows(s.num_owned);
  for (std::size_t i = 0; i < got_rows.size(); ++i)
    for (Eigen::Index c = 0; c < k; ++c) sums(got_rows[i] - s.row_begin, c) += got[i * std::size_t(k) + std::size_t(c)];
  return sums;
}

Eigen::MatrixX3d distributed_geometric_vertex_normals(const DistributedSurface& s, const Eigen::MatrixX3d& positions) {
  SurfelMesh mesh;
  mesh.faces = s.mesh.faces;
  mesh.positions = local_rows(s, positions);
  const Eigen::MatrixX3d face_normals = mesh.face_normals_from_positions();
  Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(mesh.num_vertices(), 3);
  for (Eigen::Index f = 0; f < mesh.faces.rows(); ++f)
    for (int j = 0; j < 4; ++j) sums.row(mesh.faces(f, j)) += face_normals.row(f);
  Eigen::MatrixX3d normals = sum_at_owners(s, sums);
  for (Eigen::Index v = 0; v < normals.rows(); ++v) {
    const double n = normals.row(v).norm();
    if (n > 0) normals.row(v) /= n;
  }
  return normals;
}

void write_distributed_mesh(const std::string& path, const DistributedSurface& s, const Eigen::MatrixX3d& positions,
                            const MeshAttributes& attributes, bool reverse_faces) {
  // Every rank formats its runs; a failure anywhere fails everywhere before the file exists.
  // Whether the file has vertex normals: a rank without vertices has none to show it.
  int normals = attributes.vertex_normals.rows() > 0 ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &normals, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MeshAttributes declared;  // what the layout reads: the same on every rank
  declared.comments = attributes.comments;
  if (normals) declared.vertex_normals = Eigen::MatrixX3d::Zero(1, 3);
  for (const auto& [name, v] : attributes.vertex_scalars) declared.vertex_scalars[name] = Eigen::VectorXd();
  declared.face_normals = attributes.face_normals;
  declared.face_scalars = attributes.face_scalars;
  std::optional<std::string> failure;
  std::string header;
  std::vector<std::int64_t> keys;  // per run: section (0 vertices, 1 faces), first id, bytes
  std::vector<std::string> blocks;
  try {
    if (positions.rows() != s.num_owned)
      throw IoError("mesh file '" + path + "': expected one position per owned vertex");
    const MeshFileLayout layout = mesh_file_layout(path, s.num_vertices, s.num_faces, declared);
    header = mesh_file_header(layout);
    for (const Run& run : runs_of(s.vertex_ids, s.num_owned)) {
      MeshAttributes part;
      if (layout.vertex_normals) {
        if (attributes.vertex_normals.rows() != s.num_owned)
          throw IoError("mesh file '" + path + "': expected one normal per owned vertex");
        part.vertex_normals = attributes.vertex_normals.middleRows(run.begin, run.count);
      }
      for (const auto& [name, v] : attributes.vertex_scalars) {
        if (v.size() != s.num_owned)
          throw IoError("mesh file '" + path + "': scalar '" + name + "' needs one value per owned vertex");
        part.vertex_scalars[name] = v.segment(run.begin, run.count);
      }
      blocks.push_back(mesh_file_vertices(layout, run.first, positions.middleRows(run.begin, run.count), part));
      keys.insert(keys.end(), {0, run.first, std::int64_t(blocks.back().size())});
    }
    for (const Run& run : runs_of(s.face_ids, s.mesh.num_faces())) {
      QuadFaces faces(run.count, 4);
      for (Eigen::Index f = 0; f < run.count; ++f)
        for (int c = 0; c < 4; ++c)
          faces(f, c) = s.vertex_ids[std::size_t(s.mesh.faces(run.begin + f, reverse_faces ? 3 - c : c))];
      blocks.push_back(mesh_file_faces(layout, faces));
      keys.insert(keys.end(), {1, run.first, std::int64_t(blocks.back().size())});
    }
  } catch (const Error& e) {
    failure = e.what();
  }
  rethrow_everywhere(failure);
  write_runs(path, s, header, keys, blocks);
}

void write_distributed_scalars(const std::string& path, const DistributedSurface& s, const Eigen::VectorXd& values,
                               const std::vector<std::string>& comments) {
  std::optional<std::string> failure;
  std::vector<std::int64_t> keys;
  std::vector<std::string> blocks;
  try {
    if (values.size() != s.num_owned) throw IoError("scalars file '" + path + "': expected one value per owned vertex");
    for (const Run& run : runs_of(s.vertex_ids, s.num_owned)) {
      blocks.push_back(scalars_file_rows(path, values.segment(run.begin, run.count), run.first));
      keys.insert(keys.end(), {0, run.first, std::int64_t(blocks.back().size())});
    }
  } catch (const Error& e) {
    failure = e.what();
  }
  rethrow_everywhere(failure);
  write_runs(path, s, scalars_file_header(comments), keys, blocks);
}

}  // namespace corrlap

#pragma once
// Corner storage of a FaceList read face by face from a file that announces only the number of
// faces (PLY, OFF) (internal). Growing the corners by doubling would hold up to three times their
// bytes while copying, and assuming triangles doubles the array of a quad mesh (every digital
// surface). So the first face's degree times the face count is reserved, exact for a mesh of
// triangles only or quads only; a face that does not fit reserves, for the faces left, the mean
// degree so far plus 1/16, never more corners than the rest of the file can hold.
#include <algorithm>
#include <corrlap/core/face_list.hpp>
#include <cstddef>

namespace corrlap::io_detail {

class CornerReserve {
 public:
  CornerReserve(FaceList& faces, std::size_t face_count) : faces_(faces), count_(face_count) {
    faces_.reserve(face_count, 0);
  }
  /// Call before the face of n corners is started; most_left: the most corners the rest of the
  /// file can hold, this face's included (it bounds what a corrupt file can make us allocate).
  void before_face(std::size_t n, std::size_t most_left) {
    const std::size_t have = faces_.num_corners();
    if (have + n <= reserved_) return;
    const std::size_t done = faces_.size();
    const double left = count_ > done + 1 ? double(count_ - done - 1) : 0.0;
    const double rest = done == 0 ? double(n) * left : double(have + n) / double(done + 1) * left * 17.0 / 16.0;
    reserved_ = have + std::size_t(std::min(double(n) + rest, double(std::max(most_left, n))));
    faces_.reserve(count_, reserved_);
  }

 private:
  FaceList& faces_;
  std::size_t count_, reserved_ = 0;
};

}  // namespace corrlap::io_detail

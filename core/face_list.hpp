#pragma once
// Faces of any degree in one flat array (compressed rows): the corners of all faces back to back
// plus one offset per face. A mesh of millions of faces costs two allocations instead of one per
// face, and 4 bytes per corner plus 8 per face instead of ~40 per face.
#include <cstddef>
#include <initializer_list>
#include <span>
#include <type_traits>
#include <vector>

namespace corrlap {

class FaceList {
 public:
  /// Iterating gives one std::span of corner ids per face (std::span<int> for a non-const list).
  template <bool Const>
  class Iterator {
   public:
    using List = std::conditional_t<Const, const FaceList, FaceList>;
    using value_type = std::span<std::conditional_t<Const, const int, int>>;
    using difference_type = std::ptrdiff_t;
    Iterator() = default;
    Iterator(List* list, std::size_t f) : list_(list), f_(f) {}
    value_type operator*() const { return (*list_)[f_]; }
    Iterator& operator++() {
      ++f_;
      return *this;
    }
    Iterator operator++(int) {
      Iterator old = *this;
      ++f_;
      return old;
    }
    bool operator==(const Iterator& o) const { return f_ == o.f_; }

   private:
    List* list_ = nullptr;
    std::size_t f_ = 0;
  };
  using const_iterator = Iterator<true>;
  using iterator = Iterator<false>;

  FaceList() = default;
  FaceList(std::initializer_list<std::initializer_list<int>> faces) {
    for (const auto& f : faces) push_back(f);
  }

  std::size_t size() const { return offsets_.size() - 1; }
  bool empty() const { return size() == 0; }
  /// Corners of all faces together.
  std::size_t num_corners() const { return corners_.size(); }

  std::span<const int> operator[](std::size_t f) const {
    return {corners_.data() + offsets_[f], offsets_[f + 1] - offsets_[f]};
  }
  std::span<int> operator[](std::size_t f) { return {corners_.data() + offsets_[f], offsets_[f + 1] - offsets_[f]}; }
  std::span<const int> back() const { return (*this)[size() - 1]; }
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size()}; }
  iterator begin() { return {this, 0}; }
  iterator end() { return {this, size()}; }

  void push_back(std::span<const int> face) {
    corners_.insert(corners_.end(), face.begin(), face.end());
    offsets_.push_back(corners_.size());
  }
  void push_back(std::initializer_list<int> face) { push_back(std::span<const int>(face.begin(), face.size())); }
  void push_back(const std::vector<int>& face) { push_back(std::span<const int>(face)); }
  void pop_back() {
    offsets_.pop_back();
    corners_.resize(offsets_.back());
  }
  /// Appends one corner to the last face (building a face corner by corner: start it with
  /// start_face()).
  void start_face() { offsets_.push_back(corners_.size()); }
  void add_corner(int id) {
    corners_.push_back(id);
    ++offsets_.back();
  }

  /// Room for `faces` faces with `corners` corners in all: no reallocation while they are added.
  void reserve(std::size_t faces, std::size_t corners) {
    offsets_.reserve(faces + 1);
    corners_.reserve(corners);
  }
  void clear() {
    corners_.clear();
    offsets_.assign(1, 0);
  }

  /// The flat arrays: corners of face f are corners()[offsets()[f] .. offsets()[f + 1]).
  const std::vector<int>& corners() const { return corners_; }
  const std::vector<std::size_t>& offsets() const { return offsets_; }

  bool operator==(const FaceList&) const = default;

 private:
  std::vector<int> corners_;
  std::vector<std::size_t> offsets_{0};
};

}  // namespace corrlap

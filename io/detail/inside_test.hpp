#pragma once
// Deciding inside / outside for one typed value (internal), shared by the streamed readers
// (io/volume_io.cpp) and by volumes in memory (pipeline/load_surface.cpp), so that a value is
// inside by the same rule whatever it came from.
#include <algorithm>
#include <cmath>
#include <corrlap/io/voxel_values.hpp>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

namespace corrlap::io_detail {

/// The rule decided in the value's own type, so that no value is converted to a type that cannot
/// hold it: an integer is above a threshold iff it is >= the smallest integer above it, and equals
/// a label only if the label is an integer of its range (exact for 64-bit values, which a double
/// cannot all represent); float32 and float64 compare as doubles (exact); bool is 0 or 1.
template <class T>
struct InsideTest {
  InsideRule rule;
  T bound{};          // Above: the lowest inside integer; Label: the label in T
  bool none = false;  // no value of T can be inside

  explicit InsideTest(const InsideRule& r) : rule(r) {
    if constexpr (std::is_integral_v<T>) {
      using L = std::numeric_limits<T>;
      if (rule.kind == InsideRule::Kind::Above) {
        const double f = std::floor(rule.value);
        if (f < double(L::lowest()))
          bound = L::lowest();
        else if (f >= double(L::max()))
          none = true;
        else
          bound = T(T(f) + 1);  // f is in range here, so the conversion is exact
      } else if (rule.kind == InsideRule::Kind::Label) {
        // [lowest, 2^digits) is exactly T's range, and both ends are exact doubles.
        const double v = rule.value;
        if (v != std::floor(v) || v < double(L::lowest()) || v >= std::ldexp(1.0, L::digits))
          none = true;
        else
          bound = T(v);
      }
    }
  }
  bool inside(T v) const {
    switch (rule.kind) {
      case InsideRule::Kind::Nonzero:
        return v != T(0);
      case InsideRule::Kind::Above:
        if constexpr (std::is_integral_v<T>)
          return v >= bound;
        else
          return double(v) > rule.value;
      case InsideRule::Kind::Label:
        if constexpr (std::is_integral_v<T>)
          return v == bound;
        else
          return double(v) == rule.value;
    }
    return false;
  }
  static bool is_nan(T v) {
    if constexpr (std::is_floating_point_v<T>)
      return std::isnan(v);
    else
      return false;
  }
};

/// The value of type T at p (any alignment), its bytes reversed first when Swapped. bool: any
/// nonzero byte is true.
template <class T, bool Swapped>
T read_value(const void* p) {
  if constexpr (std::is_same_v<T, bool>) {
    return *static_cast<const unsigned char*>(p) != 0;
  } else {
    unsigned char bytes[sizeof(T)];
    std::memcpy(bytes, p, sizeof(T));
    if constexpr (Swapped) std::reverse(bytes, bytes + sizeof(T));
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    return v;
  }
}

/// Calls f(T{}) with the C++ type of `type`.
template <class F>
decltype(auto) visit_value_type(VoxelValueType type, F&& f) {
  switch (type) {
    case VoxelValueType::Bool:
      return f(bool{});
    case VoxelValueType::Int8:
      return f(std::int8_t{});
    case VoxelValueType::Int16:
      return f(std::int16_t{});
    case VoxelValueType::Int32:
      return f(std::int32_t{});
    case VoxelValueType::Int64:
      return f(std::int64_t{});
    case VoxelValueType::UInt8:
      return f(std::uint8_t{});
    case VoxelValueType::UInt16:
      return f(std::uint16_t{});
    case VoxelValueType::UInt32:
      return f(std::uint32_t{});
    case VoxelValueType::UInt64:
      return f(std::uint64_t{});
    case VoxelValueType::Float32:
      return f(float{});
    case VoxelValueType::Float64:
      return f(double{});
  }
  throw std::logic_error("visit_value_type: unknown VoxelValueType");
}

}  // namespace corrlap::io_detail

#include "voxel_values.hpp"

#include <corrlap/core/error.hpp>
#include <corrlap/io/detail/checked.hpp>
#include <stdexcept>

namespace corrlap {

std::size_t value_bytes(VoxelValueType type) {
  switch (type) {
    case VoxelValueType::Bool:
    case VoxelValueType::Int8:
    case VoxelValueType::UInt8:
      return 1;
    case VoxelValueType::Int16:
    case VoxelValueType::UInt16:
      return 2;
    case VoxelValueType::Int32:
    case VoxelValueType::UInt32:
    case VoxelValueType::Float32:
      return 4;
    case VoxelValueType::Int64:
    case VoxelValueType::UInt64:
    case VoxelValueType::Float64:
      return 8;
  }
  throw std::logic_error("value_bytes: unknown VoxelValueType");
}

std::string value_type_name(VoxelValueType type) {
  switch (type) {
    case VoxelValueType::Bool:
      return "bool";
    case VoxelValueType::Int8:
      return "int8";
    case VoxelValueType::Int16:
      return "int16";
    case VoxelValueType::Int32:
      return "int32";
    case VoxelValueType::Int64:
      return "int64";
    case VoxelValueType::UInt8:
      return "uint8";
    case VoxelValueType::UInt16:
      return "uint16";
    case VoxelValueType::UInt32:
      return "uint32";
    case VoxelValueType::UInt64:
      return "uint64";
    case VoxelValueType::Float32:
      return "float32";
    case VoxelValueType::Float64:
      return "float64";
  }
  throw std::logic_error("value_type_name: unknown VoxelValueType");
}

std::string InsideRule::describe() const {
  switch (kind) {
    case Kind::Nonzero:
      return "nonzero";
    case Kind::Above:
      return "above the threshold " + io_detail::readable_number(value);
    case Kind::Label:
      return "equal to the label " + io_detail::readable_number(value);
  }
  throw std::logic_error("InsideRule::describe: unknown kind");
}

Eigen::Matrix4d VolumeGeometry::affine() const {
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a.topLeftCorner<3, 3>() = direction * spacing.asDiagonal();
  a.topRightCorner<3, 1>() = origin;
  return a;
}

std::string space_name(PhysicalSpace space) {
  switch (space) {
    case PhysicalSpace::Unknown:
      return "unknown";
    case PhysicalSpace::RAS:
      return "RAS";
    case PhysicalSpace::LAS:
      return "LAS";
    case PhysicalSpace::LPS:
      return "LPS";
  }
  throw std::logic_error("space_name: unknown PhysicalSpace");
}

namespace {

// The signs of a known space's axes against RAS's.
Eigen::Vector3d signs_from_ras(PhysicalSpace space) {
  switch (space) {
    case PhysicalSpace::LAS:
      return {-1, 1, 1};
    case PhysicalSpace::LPS:
      return {-1, -1, 1};
    default:
      return {1, 1, 1};
  }
}

}  // namespace

Eigen::Matrix3d space_change(PhysicalSpace from, PhysicalSpace to) {
  if (from == to) return Eigen::Matrix3d::Identity();
  if (from == PhysicalSpace::Unknown || to == PhysicalSpace::Unknown)
    throw InputError("cannot convert physical coordinates from the space " + space_name(from) + " to " +
                     space_name(to) + ": an unknown space has no anatomical axes to flip");
  return signs_from_ras(from).cwiseProduct(signs_from_ras(to)).asDiagonal();
}

VolumeGeometry VolumeGeometry::in_space(PhysicalSpace to) const {
  const Eigen::Matrix3d flip = space_change(space, to);
  VolumeGeometry g = *this;
  g.origin = flip * origin;
  g.direction = flip * direction;
  g.space = to;
  return g;
}

}  // namespace corrlap

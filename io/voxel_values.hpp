#pragma once
// What a volume's voxels hold and where they are: the element type of the values, the rule that
// makes a value inside, and the map from voxel indices to physical coordinates. Shared by every
// volume reader and by volumes in memory (numpy arrays), so that a value means the same thing
// whatever it came from (docs/io.md, "Volumes").
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string>

namespace corrlap {

/// The element type of voxel values (numpy's bool, int8 ... uint64, float32, float64; the types of
/// NIfTI, NRRD and MetaImage files map onto these).
enum class VoxelValueType { Bool, Int8, Int16, Int32, Int64, UInt8, UInt16, UInt32, UInt64, Float32, Float64 };

/// Bytes per value.
std::size_t value_bytes(VoxelValueType type);
/// numpy's name of the type ("uint8", "float32", "bool").
std::string value_type_name(VoxelValueType type);

/// Which voxel values are inside the shape.
struct InsideRule {
  enum class Kind {
    Nonzero,  ///< every value != 0 (a binary mask or a one-label segmentation)
    Above,    ///< value > threshold (a grey-level volume)
    Label,    ///< value == label (one label of a multi-label segmentation)
  };
  Kind kind = Kind::Nonzero;
  double value = 0.0;  ///< the threshold or the label

  static InsideRule nonzero() { return {}; }
  static InsideRule above(double threshold) { return {Kind::Above, threshold}; }
  static InsideRule label(double label) { return {Kind::Label, label}; }
  /// "nonzero", "above the threshold 0.5", "equal to the label 3": completes "no voxel ...".
  std::string describe() const;
};

/// The anatomical space that physical coordinates are in, named by the direction in which each
/// axis grows: RAS (x towards the patient's Right, y Anterior, z Superior: NIfTI, nibabel), LPS (Left, Posterior,
/// Superior: DICOM, ITK, MetaImage, Slicer's files) and LAS (NRRD names it). Unknown: a space without anatomy (NRRD's
/// scanner-xyz, 3D-right-handed, "space dimension", and every format without one). Converting between known spaces
/// flips axes.
enum class PhysicalSpace { Unknown, RAS, LAS, LPS };
/// "RAS", "LAS", "LPS" or "unknown".
std::string space_name(PhysicalSpace space);
/// The diagonal map of physical coordinates in `from` to coordinates in `to` (x and y flipped
/// between RAS and LPS); the identity when they are equal. InputError when one of them is Unknown
/// and they differ: no anatomy says which way the axes go.
Eigen::Matrix3d space_change(PhysicalSpace from, PhysicalSpace to);

/// The map from voxel indices to physical coordinates (millimetres for medical formats):
/// physical = origin + direction * diag(spacing) * index, index (i, j, k) the voxel's centre.
/// The identity for files without one (.vol, .raw, binvox, .vox, .npy).
struct VolumeGeometry {
  Eigen::Vector3d spacing = Eigen::Vector3d::Ones();        ///< voxel side lengths along i, j, k (> 0)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();         ///< the physical position of voxel (0, 0, 0)
  Eigen::Matrix3d direction = Eigen::Matrix3d::Identity();  ///< columns: the unit physical axes of i, j, k
  PhysicalSpace space = PhysicalSpace::Unknown;             ///< the space of the physical coordinates

  /// The 4 by 4 homogeneous map index -> physical (NIfTI's sform, nibabel's affine in RAS for
  /// NIfTI; in the file's own space for the other formats).
  Eigen::Matrix4d affine() const;
  Eigen::Vector3d to_physical(const Eigen::Vector3d& index) const {
    return origin + direction * spacing.cwiseProduct(index);
  }
  bool isotropic() const { return spacing.maxCoeff() == spacing.minCoeff(); }
  /// The same voxels placed in the space `to` (origin and direction flipped by space_change); throws
  /// as space_change.
  VolumeGeometry in_space(PhysicalSpace to) const;
};

}  // namespace corrlap

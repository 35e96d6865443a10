#pragma once
// The volume readers and writers, one per format and file (internal; dispatched by
// io/volume_io.cpp). A reader parses the header, checks the announced sizes and type (IoError
// naming the file, the field and the limit) before anything is allocated, and streams the values
// into the sink (io/detail/volume_stream.hpp). A writer writes through io/detail/output_file.hpp
// (no half-written file).
#include <corrlap/io/detail/volume_stream.hpp>
#include <corrlap/io/volume_io.hpp>
#include <string>

namespace corrlap::io_detail {

/// NRRD (.nrrd, attached header; .nhdr + detached data): io/nrrd.cpp.
void read_nrrd(const std::string& path, VoxelSink& sink);
void write_nrrd(const std::string& path, const VolumeData& volume);
/// NIfTI-1 and NIfTI-2 (.nii, .nii.gz): io/nifti.cpp.
void read_nifti(const std::string& path, VoxelSink& sink);
void write_nifti(const std::string& path, const VolumeData& volume);
/// MetaImage (.mha, .mhd + data file): io/metaimage.cpp.
void read_metaimage(const std::string& path, VoxelSink& sink);
void write_metaimage(const std::string& path, const VolumeData& volume);
/// binvox (.binvox): io/binvox.cpp.
void read_binvox(const std::string& path, VoxelSink& sink);
void write_binvox(const std::string& path, const VolumeData& volume);
/// MagicaVoxel (.vox), values = palette indices (0: empty): io/magicavoxel.cpp.
void read_magicavoxel(const std::string& path, VoxelSink& sink);
/// numpy (.npy): io/npy.cpp.
void read_npy(const std::string& path, VoxelSink& sink);
void write_npy(const std::string& path, const VolumeData& volume);
/// TIFF stacks (.tif, .tiff: multi-page; a folder of single-page slices in name order): io/tiff.cpp.
void read_tiff(const std::string& path, VoxelSink& sink);
void write_tiff(const std::string& path, const VolumeData& volume);

}  // namespace corrlap::io_detail

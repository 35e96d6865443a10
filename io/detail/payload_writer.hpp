#pragma once
// The values of a volume written after its header (internal): raw, or deflated as one zlib or gzip
// stream a chunk at a time, so that a compressed volume is never held whole (NIfTI .nii.gz,
// MetaImage CompressedData).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

namespace corrlap::io_detail {

class PayloadWriter {
 public:
  enum class Encoding { Raw, Zlib, Gzip };
  /// Writes to `file` (owned by the caller, e.g. an OutputFile); IoError naming `path` when a
  /// compressed encoding is asked of a build without zlib.
  PayloadWriter(std::FILE* file, const std::string& path, Encoding encoding);
  ~PayloadWriter();
  PayloadWriter(const PayloadWriter&) = delete;
  PayloadWriter& operator=(const PayloadWriter&) = delete;
  void write(const void* data, std::size_t n);
  /// Ends the compressed stream (nothing for raw); the caller then commits the file.
  void finish();
  /// Bytes written to the file so far (compressed bytes when compressed).
  std::uint64_t written() const { return written_; }

 private:
  struct Deflater;
  void emit();  // the deflater's output so far, to the file
  std::FILE* file_;
  std::string path_;
  std::unique_ptr<Deflater> deflater_;
  std::uint64_t written_ = 0;
};

}  // namespace corrlap::io_detail

#pragma once
// Output files that never end up half-written (internal). The data goes to a temporary file beside
// the destination, which commit() flushes, closes and renames onto it; when anything fails first
// (an exception, a full disk), the temporary file is removed and the destination is untouched.
// An existing special file (/dev/null, a pipe) is written directly: nothing can be renamed onto it.
#include <cmath>
#include <cstdio>
#include <string>

namespace corrlap::io_detail {

class OutputFile {
 public:
  /// Opens "<path>.tmp-<pid>" for writing; `what` names the format in messages ("OBJ", ...).
  /// Throws IoError when it cannot be created.
  OutputFile(const std::string& path, const char* what, bool binary = false);
  /// Removes the temporary file unless commit() succeeded.
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  std::FILE* get() const { return file_; }
  /// Flushes and closes the file and renames it onto the destination. Throws IoError on a write
  /// error (disk full, ...), leaving the destination as it was.
  void commit();

 private:
  std::string path_, temp_, what_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

/// Throws IoError "<what> file '<path>': <element> <index> is not finite (<value>)" when v is NaN
/// or infinite: no output file holds a NaN.
void require_finite(double v, const std::string& path, const char* what, const std::string& element, long long index);

}  // namespace corrlap::io_detail

#include "output_file.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <corrlap/core/error.hpp>
#include <cstring>

namespace corrlap::io_detail {

namespace {
// /dev/null, a pipe: written in place, as nothing can be renamed onto them (a rename would
// replace the device by a regular file).
bool is_special_file(const std::string& path) {
  struct stat s {};
  return ::stat(path.c_str(), &s) == 0 && !S_ISREG(s.st_mode) && !S_ISDIR(s.st_mode);
}
}  // namespace

OutputFile::OutputFile(const std::string& path, const char* what, bool binary)
    : path_(path), temp_(is_special_file(path) ? path : path + ".tmp-" + std::to_string(::getpid())), what_(what) {
  file_ = std::fopen(temp_.c_str(), binary ? "wb" : "w");
  if (!file_) throw IoError(what_ + " file '" + path_ + "': cannot open for writing: " + std::strerror(errno));
}

OutputFile::~OutputFile() {
  if (file_) std::fclose(file_);
  if (!committed_ && temp_ != path_) std::remove(temp_.c_str());
}

void OutputFile::commit() {
  const bool write_error = std::ferror(file_) != 0 || std::fflush(file_) != 0;
  const bool close_error = std::fclose(file_) != 0;
  file_ = nullptr;
  if (write_error || close_error) throw IoError(what_ + " file '" + path_ + "': write error");
  if (temp_ != path_ && std::rename(temp_.c_str(), path_.c_str()) != 0)
    throw IoError(what_ + " file '" + path_ + "': cannot replace it: " + std::strerror(errno));
  committed_ = true;
}

void require_finite(double v, const std::string& path, const char* what, const std::string& element, long long index) {
  if (std::isfinite(v)) return;
  throw IoError(std::string(what) + " file '" + path + "': " + element + " " + std::to_string(index) +
                " is not finite (" +
                (std::isnan(v) ? "nan"
                 : v > 0       ? "inf"
                               : "-inf") +
                "); nothing was written");
}

}  // namespace corrlap::io_detail

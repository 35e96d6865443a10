#pragma once
// Buffered output for the text (and binary) writers (internal). Values are formatted with
// std::to_chars into a 1 MiB buffer flushed by fwrite: no stdio call per value, and doubles come
// out byte for byte as printf("%.17g") would print them (17 significant digits: exact round trip).
#include <charconv>
#include <concepts>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include "output_file.hpp"

namespace corrlap::io_detail {

class TextWriter {
 public:
  /// Opens the output as OutputFile does (a temporary file renamed by commit()).
  TextWriter(const std::string& path, const char* what, bool binary = false, std::size_t buffer_bytes = 1 << 20);

  void write(char c) {
    if (pos_ == capacity_) flush();
    buffer_[pos_++] = c;
  }
  void write(std::string_view s);
  void write_bytes(const void* data, std::size_t n) { write(std::string_view(static_cast<const char*>(data), n)); }
  /// As printf("%.17g", v): the shortest form of std::to_chars would differ from the files we wrote before.
  void write_double(double v) {
    reserve(kMaxNumber);
    pos_ =
        std::size_t(std::to_chars(&buffer_[pos_], &buffer_[pos_ + kMaxNumber], v, std::chars_format::general, 17).ptr -
                    buffer_.get());
  }
  template <std::integral I>
  void write_int(I v) {
    reserve(kMaxNumber);
    pos_ = std::size_t(std::to_chars(&buffer_[pos_], &buffer_[pos_ + kMaxNumber], v).ptr - buffer_.get());
  }

  /// Flushes the buffer and commits the file (OutputFile::commit: IoError on a write error).
  void commit();

 private:
  // "-2.2250738585072014e-308" has 24 characters, a 64-bit integer at most 20.
  static constexpr std::size_t kMaxNumber = 32;
  void reserve(std::size_t n) {
    if (capacity_ - pos_ < n) flush();
  }
  void flush();

  OutputFile file_;
  std::size_t capacity_;
  std::unique_ptr<char[]> buffer_;
  std::size_t pos_ = 0;
};

}  // namespace corrlap::io_detail

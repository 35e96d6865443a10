#include "text_writer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

namespace corrlap::io_detail {

TextWriter::TextWriter(const std::string& path, const char* what, bool binary, std::size_t buffer_bytes)
    : file_(path, what, binary), capacity_(std::max(buffer_bytes, 2 * kMaxNumber)), buffer_(new char[capacity_]) {}

void TextWriter::write(std::string_view s) {
  while (!s.empty()) {
    if (pos_ == capacity_) flush();
    const std::size_t n = std::min(s.size(), capacity_ - pos_);
    std::memcpy(&buffer_[pos_], s.data(), n);
    pos_ += n;
    s.remove_prefix(n);
  }
}

// A failed fwrite sets the stream's error flag, which commit() reports as a write error.
void TextWriter::flush() {
  if (pos_ != 0) std::fwrite(buffer_.get(), 1, pos_, file_.get());
  pos_ = 0;
}

void TextWriter::commit() {
  flush();
  file_.commit();
}

}  // namespace corrlap::io_detail

#pragma once
// Lines of a text file read in large blocks (internal). The readers parse each line in place with
// std::from_chars (io/detail/tokens.hpp): no stream, no string per line or per token. A line split
// across two blocks is moved to the front of the buffer before the next block is read; a line
// longer than the buffer grows it. The same blocks serve raw bytes after a text header (binary PLY):
// fill / buffered / consume.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace corrlap::io_detail {

class LineReader {
 public:
  static constexpr std::size_t kDefaultBlock = std::size_t{4} << 20;

  /// Opens path for reading; is_open() tells whether it could (the caller names the format).
  explicit LineReader(const std::string& path, std::size_t block_bytes = kDefaultBlock);
  ~LineReader();
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  bool is_open() const { return file_ != nullptr; }
  /// The next line without its '\n' (a '\r' before it is kept), valid until the next call; false
  /// at the end of the file. Splits lines as std::getline does: a last line without '\n' counts,
  /// an empty file has no line.
  bool next(std::string_view& line);
  /// 1-based number of the line next() returned last (0 before the first).
  std::size_t line_number() const { return line_; }
  /// True when reading failed (as opposed to ending).
  bool error() const { return error_; }
  /// Bytes of the file (at opening).
  std::uint64_t file_size() const { return size_; }
  /// Back to the first line, for a second pass.
  void rewind();

  /// At least n unread bytes in the buffer (it grows when n is larger); false when the file ends
  /// first. Invalidates the views next() and buffered() returned.
  bool fill(std::size_t n);
  /// The unread bytes in the buffer (possibly none), valid until the next call to next or fill.
  std::string_view buffered() const { return {buffer_.data() + begin_, end_ - begin_}; }
  /// Marks the first n bytes of buffered() as read.
  void consume(std::size_t n) { begin_ += n; }
  /// Offset in the file of the first unread byte (after next(): the start of the following line).
  std::uint64_t offset() const { return base_ + begin_; }

 private:
  bool refill();

  std::FILE* file_ = nullptr;
  std::vector<char> buffer_;
  std::size_t begin_ = 0, end_ = 0, line_ = 0;
  std::uint64_t size_ = 0, base_ = 0;  // base_: file offset of buffer_[0]
  bool eof_ = false, error_ = false;
};

/// s without one trailing '\r' (CRLF files).
inline std::string_view without_cr(std::string_view s) {
  if (!s.empty() && s.back() == '\r') s.remove_suffix(1);
  return s;
}

}  // namespace corrlap::io_detail

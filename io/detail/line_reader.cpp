#include "line_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cstring>

namespace corrlap::io_detail {

LineReader::LineReader(const std::string& path, std::size_t block_bytes) : file_(std::fopen(path.c_str(), "rb")) {
  struct stat st {};
  if (file_ && ::fstat(::fileno(file_), &st) == 0) size_ = std::uint64_t(st.st_size);
  // No bigger than the file (+1 to see its end in one read): a small file must not cost a cleared
  // 4 MiB block (the fuzzer opens 100 000 of them). A file that grows is still read: refill grows
  // the buffer.
  buffer_.resize(std::max<std::size_t>(1, std::min<std::uint64_t>(block_bytes, size_ + 1)));
  // The blocks are ours: stdio's own buffer would only add a copy.
  if (file_) std::setvbuf(file_, nullptr, _IONBF, 0);
}

LineReader::~LineReader() {
  if (file_) std::fclose(file_);
}

void LineReader::rewind() {
  if (!file_) return;
  std::rewind(file_);
  begin_ = end_ = line_ = 0;
  base_ = 0;
  eof_ = error_ = false;
}

// Keeps the unfinished line [begin_, end_) at the front and appends the next block.
bool LineReader::refill() {
  if (eof_ || !file_) return false;
  if (begin_ != 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
    end_ -= begin_;
    base_ += begin_;
    begin_ = 0;
  }
  if (end_ == buffer_.size()) buffer_.resize(2 * buffer_.size());
  const std::size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
  end_ += got;
  if (got == 0) {
    eof_ = true;
    error_ = std::ferror(file_) != 0;
  }
  return got != 0;
}

bool LineReader::fill(std::size_t n) {
  while (end_ - begin_ < n)
    if (!refill()) return false;
  return true;
}

bool LineReader::next(std::string_view& line) {
  std::size_t searched = begin_;  // bytes before this are known to hold no '\n'
  for (;;) {
    const char* data = buffer_.data();
    if (const void* nl = std::memchr(data + searched, '\n', end_ - searched)) {
      const auto at = std::size_t(static_cast<const char*>(nl) - data);
      line = std::string_view(data + begin_, at - begin_);
      begin_ = at + 1;
      ++line_;
      return true;
    }
    const std::size_t offset = end_ - begin_;
    if (!refill()) break;
    searched = begin_ + offset;
  }
  if (begin_ == end_) return false;
  line = std::string_view(buffer_.data() + begin_, end_ - begin_);  // last line, no '\n'
  begin_ = end_;
  ++line_;
  return true;
}

}  // namespace corrlap::io_detail

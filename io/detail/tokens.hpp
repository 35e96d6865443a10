#pragma once
// Whitespace-separated tokens of one line and their conversion with std::from_chars (internal).
// Whitespace is what `std::istream >> std::string` skips in the C locale (the readers used streams
// before and their files keep reading the same).
#include <charconv>
#include <string_view>
#include <system_error>

namespace corrlap::io_detail {

inline bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f' || c == '\n'; }

class Tokens {
 public:
  explicit Tokens(std::string_view line) : rest_(line) {}
  /// The next token; false when only whitespace is left.
  bool next(std::string_view& token) {
    std::size_t b = 0;
    while (b < rest_.size() && is_blank(rest_[b])) ++b;
    if (b == rest_.size()) {
      rest_ = {};
      return false;
    }
    std::size_t e = b + 1;
    while (e < rest_.size() && !is_blank(rest_[e])) ++e;
    token = rest_.substr(b, e - b);
    rest_.remove_prefix(e);
    return true;
  }
  /// Whether anything but whitespace is left (does not consume it).
  bool more() const {
    for (char c : rest_)
      if (!is_blank(c)) return true;
    return false;
  }

 private:
  std::string_view rest_;
};

/// The whole of s as a number (integer or double, from_chars rules: no '+', no hex, no spaces).
template <class T>
bool parse_number(std::string_view s, T& value) {
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, value);
  return ec == std::errc() && ptr == end;
}

}  // namespace corrlap::io_detail

#pragma once
// The study tables' CSV conventions (internal): every number through `number` (17 significant
// digits; an empty field for an undefined value), a header line checked on reading, and errors
// naming the file and line.
#include <cmath>
#include <corrlap/core/error.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace corrlap::detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The one writer of numbers in study files: a value that is not finite (an undefined relative
// error, an order or interval without enough points) is an empty field, never "nan" or "inf",
// which spreadsheets and most CSV readers do not take as numbers (docs/studies.md).
inline std::string number(double v) {
  if (!std::isfinite(v)) return "";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

inline std::FILE* open_csv(const std::string& path, bool append, const char* header) {
  const bool fresh = !append || !std::filesystem::exists(path) || std::filesystem::file_size(path) == 0;
  std::FILE* f = std::fopen(path.c_str(), fresh ? "w" : "a");
  if (!f) throw IoError("study: cannot write '" + path + "'");
  if (fresh) std::fprintf(f, "%s\n", header);
  return f;
}

inline void close_csv(std::FILE* f, const std::string& path) {
  const bool bad = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || bad) throw IoError("study: write error on '" + path + "' (disk full?)");
}

// A CSV file as rows of fields addressed by column name.
class CsvReader {
 public:
  CsvReader(const std::string& path, const char* expected_header) : path_(path) {
    std::ifstream in(path);
    if (!in) throw IoError("study: cannot open '" + path + "'");
    std::string line;
    if (!std::getline(in, line)) throw IoError("study: '" + path + "' is empty");
    if (line != expected_header)
      throw IoError("study: '" + path + "': unexpected header '" + line.substr(0, 120) + "' (expected '" +
                    expected_header + "')");
    columns_ = split(line).size();
    for (std::size_t lineno = 2; std::getline(in, line); ++lineno) {
      if (line.empty()) continue;
      std::vector<std::string> fields = split(line);
      if (fields.size() != columns_)
        throw IoError("study: '" + path + "', line " + std::to_string(lineno) + ": " + std::to_string(fields.size()) +
                      " fields, expected " + std::to_string(columns_) + " (an interrupted write? remove that line)");
      rows_.push_back({lineno, std::move(fields)});
    }
  }
  struct Row {
    std::size_t line;
    std::vector<std::string> fields;
  };
  const std::vector<Row>& rows() const { return rows_; }
  /// A value that may be undefined: an empty field (or "nan", as files written before the empty
  /// convention hold) is NaN.
  double number(const Row& r, std::size_t column) const {
    const std::string& s = r.fields[column];
    if (s.empty() || s == "nan") return kNaN;
    return required_number(r, column);
  }
  /// A value every row has (h, centre, counts): an empty field is an error naming the line.
  double required_number(const Row& r, std::size_t column) const {
    const std::string& s = r.fields[column];
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(v))
      throw IoError("study: '" + path_ + "', line " + std::to_string(r.line) + ", column " +
                    std::to_string(column + 1) + ": '" + s + "' is not a number");
    return v;
  }
  /// A count or index: a whole number in [0, 2^53].
  long long required_integer(const Row& r, std::size_t column) const {
    const double v = required_number(r, column);
    if (!(v >= 0.0 && v <= 0x1.0p53) || v != std::floor(v))
      throw IoError("study: '" + path_ + "', line " + std::to_string(r.line) + ", column " +
                    std::to_string(column + 1) + ": '" + r.fields[column] + "' is not a count");
    return (long long)v;
  }

 private:
  static std::vector<std::string> split(const std::string& line) {
    std::vector<std::string> out;
    std::string field;
    std::istringstream ss(line);
    while (std::getline(ss, field, ',')) out.push_back(field);
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
  }
  std::string path_;
  std::size_t columns_ = 0;
  std::vector<Row> rows_;
};

}  // namespace corrlap::detail

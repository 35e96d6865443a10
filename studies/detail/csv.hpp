#pragma once
// The study tables' CSV conventions (internal): 17 significant digits, "nan" for NaN, a header
// line checked on reading, and errors naming the file and line.
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

inline std::string number(double v) {
  if (std::isnan(v)) return "nan";
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
  double number(const Row& r, std::size_t column) const {
    const std::string& s = r.fields[column];
    if (s == "nan") return kNaN;
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || end != s.c_str() + s.size())
      throw IoError("study: '" + path_ + "', line " + std::to_string(r.line) + ": '" + s + "' is not a number");
    return v;
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

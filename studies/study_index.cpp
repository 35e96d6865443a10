#include "study_index.hpp"

#include <algorithm>
#include <corrlap/core/error.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace corrlap {

namespace {

namespace fs = std::filesystem;

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// The files of `dir` whose extensions are among `extensions`, sorted by name.
std::vector<fs::path> files_in(const fs::path& dir, const std::vector<std::string>& extensions) {
  std::vector<fs::path> files;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file() &&
        std::find(extensions.begin(), extensions.end(), entry.path().extension().string()) != extensions.end())
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) fields.push_back(field);
  if (!line.empty() && line.back() == ',') fields.emplace_back();
  return fields;
}

void write_table(std::ostream& page, const fs::path& csv, int max_rows) {
  std::ifstream in(csv);
  std::string line;
  page << "<h2>" << escape(csv.filename().string()) << "</h2>\n<div class=\"table\"><table>\n";
  int rows = 0, more = 0;
  bool header = true;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!header && rows >= max_rows) {
      ++more;
      continue;
    }
    page << "<tr>";
    for (const std::string& f : split(line))
      page << (header ? "<th>" : "<td>") << escape(f) << (header ? "</th>" : "</td>");
    page << "</tr>\n";
    rows += header ? 0 : 1;
    header = false;
  }
  page << "</table></div>\n";
  if (more > 0)
    page << "<p class=\"note\">" << more << " more rows in <a href=\"" << escape(csv.filename().string()) << "\">"
         << escape(csv.filename().string()) << "</a></p>\n";
}

}  // namespace

void write_study_index(const std::string& dir, const std::string& title, int max_rows) {
  const fs::path folder(dir);
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw IoError("study index: '" + dir + "' is not a folder");
  std::ostringstream page;
  page << "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>" << escape(title) << "</title>\n<style>\n"
       << "body { font: 14px system-ui, sans-serif; margin: 2em; color: #222; }\n"
       << "img { max-width: 48%; margin: 0.5em 1% 0.5em 0; border: 1px solid #ddd; vertical-align: top; }\n"
       << "table { border-collapse: collapse; font: 12px ui-monospace, monospace; }\n"
       << "th, td { border: 1px solid #ccc; padding: 2px 6px; text-align: right; white-space: nowrap; }\n"
       << "th { background: #f0f0f0; position: sticky; top: 0; }\n"
       << ".table { max-height: 30em; max-width: 100%; overflow: auto; display: inline-block; }\n.note { color: #666; "
          "}\n"
       << "</style></head><body>\n<h1>" << escape(title) << "</h1>\n";
  const std::vector<fs::path> pictures = files_in(folder / "plots", {".png", ".svg"});
  // One picture per figure: the PNG when there are both.
  std::vector<fs::path> shown;
  for (const fs::path& p : pictures) {
    fs::path png = p;
    png.replace_extension(".png");
    if (p.extension() == ".svg" && std::find(pictures.begin(), pictures.end(), png) != pictures.end()) continue;
    shown.push_back(p);
  }
  if (!shown.empty()) {
    page << "<h2>Plots</h2>\n";
    for (const fs::path& p : shown) {
      const std::string rel = "plots/" + p.filename().string();
      page << "<a href=\"" << escape(rel) << "\"><img src=\"" << escape(rel) << "\" alt=\"" << escape(p.stem().string())
           << "\"></a>\n";
    }
  } else {
    page << "<p class=\"note\">No plots in this folder (they need python3-matplotlib).</p>\n";
  }
  for (const fs::path& csv : files_in(folder, {".csv"})) write_table(page, csv, max_rows);
  page << "</body></html>\n";
  const fs::path out = folder / "index.html", partial = folder / "index.html.partial";
  {
    std::ofstream f(partial, std::ios::binary);
    f << page.str();
    if (!f.flush()) {
      fs::remove(partial, ec);
      throw IoError("study index: cannot write '" + out.string() + "'");
    }
  }
  fs::rename(partial, out, ec);
  if (ec) {
    fs::remove(partial, ec);
    throw IoError("study index: cannot write '" + out.string() + "' (" + ec.message() + ")");
  }
}

}  // namespace corrlap

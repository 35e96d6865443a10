#pragma once
// DIR/index.html of a study folder: its plots and tables on one page to open in a browser (no
// server, no network: the pictures are the folder's own files, the tables are copied in).
#include <string>

namespace corrlap {

/// Writes DIR/index.html titled `title`: every picture of DIR/plots (PNG and SVG, by name) and every
/// CSV table of DIR (by name) as an HTML table, a long one cut after `max_rows` rows with a note
/// naming the file. A CSV field is text (quotes are not interpreted). Throws IoError when DIR is not
/// a folder or the page cannot be written; the page appears complete or not at all.
void write_study_index(const std::string& dir, const std::string& title, int max_rows = 200);

}  // namespace corrlap

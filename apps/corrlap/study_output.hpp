#pragma once
// The end of `corrlap study` (also used by `corrlap demo`): summary.csv and orders.csv from the rows
// in DIR, the fitted L2 orders on stdout, then the plots (studies/plot_study.py) unless `plots` is off.
// The tables are named on stdout in SHOWN, the folder the user sees once DIR is committed.
#include <string>

namespace corrlap::cli {

void finish_study(const std::string& dir, const std::string& shown, bool eigen, bool plots);
/// Runs studies/plot_study.py on DIR (the figures of every table there); a missing script or
/// matplotlib is a note on stderr, a failing script a warning: the tables stay.
void run_plot_script(const std::string& dir);

}  // namespace corrlap::cli

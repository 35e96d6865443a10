#pragma once
// The end of `corrlap study` (also used by `corrlap demo`): summary.csv and orders.csv from the rows
// in DIR, the fitted L2 orders on stdout, then the plots (studies/plot_study.py) unless `plots` is off.
#include <string>

namespace corrlap::cli {

void finish_study(const std::string& dir, bool eigen, bool plots);

}  // namespace corrlap::cli

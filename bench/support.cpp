#include "support.hpp"

#include <fstream>
#include <string>

namespace corrlap::bench {

namespace {
double status_mib(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) return std::stod(line.substr(std::string(key).size())) / 1024.0;
  return 0.0;
}
}  // namespace

double rss_mib() { return status_mib("VmRSS:"); }

double peak_rss_mib() { return status_mib("VmHWM:"); }

bool reset_peak_rss() {
  std::ofstream out("/proc/self/clear_refs");
  if (!out) return false;
  out << "5";
  return bool(out);
}

}  // namespace corrlap::bench

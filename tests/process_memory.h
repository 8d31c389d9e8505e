#pragma once
// Resident memory of the running test process, for tests that bound what a reader or an
// analysis costs in memory (never in time).

#include <fstream>
#include <sstream>
#include <string>
#include <utility>

namespace jointlab::testing {

/// Peak and current resident memory of this process [bytes] (/proc/self/status).
inline std::pair<double, double> memory_now() {
  std::ifstream in("/proc/self/status");
  double hwm = 0, rss = 0;
  for (std::string line; std::getline(in, line);) {
    std::istringstream ss(line.substr(line.find(':') + 1));
    if (line.rfind("VmHWM:", 0) == 0) ss >> hwm;
    if (line.rfind("VmRSS:", 0) == 0) ss >> rss;
  }
  return {hwm * 1024, rss * 1024};
}

}  // namespace jointlab::testing

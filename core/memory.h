// What one input may make jointlab allocate, checked before allocating.
//
// A reader that learns a size from a file (rows, channels, entries) prices it in bytes
// and calls check_memory first, so a lying or absurd size is an InputError naming the
// size and the limit instead of std::bad_alloc or a machine driven into swap.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <string>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab {

/// Bytes one input may cost: half the machine's physical memory (at least 1 GiB).
inline double memory_limit() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const double physical = pages > 0 && page > 0 ? static_cast<double>(pages) * page : 8e9;
  return std::max(physical / 2, 1073741824.0);
}

/// "1.5 GB" for a byte count.
inline std::string format_bytes(double bytes) {
  if (bytes >= 1e9) return fmt::format("{:.3g} GB", bytes / 1e9);
  if (bytes >= 1e6) return fmt::format("{:.3g} MB", bytes / 1e6);
  return fmt::format("{:.3g} kB", bytes / 1e3);
}

/// Throws InputError "<what> would need <bytes>, more than the limit of <limit> (half the
/// memory)" when `bytes` exceeds memory_limit(); `what` names the file and the size.
inline void check_memory(const std::string& what, double bytes) {
  const double limit = memory_limit();
  if (!(bytes <= limit)) {
    throw InputError(fmt::format("{} would need {}, more than the limit of {} (half the memory)",
                                 what, format_bytes(bytes), format_bytes(limit)));
  }
}

}  // namespace jointlab

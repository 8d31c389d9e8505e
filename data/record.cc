#include "jointlab/data/record.h"

#include <cmath>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::data {

void check_writable(const Record& record, const std::string& name) {
  if (record.channels.empty()) throw InputError(where(name, 0, "record has no channels to write"));
  if (!(record.fs > 0) || !std::isfinite(record.fs) || !std::isfinite(record.t0)) {
    throw InputError(where(
        name, 0,
        fmt::format("sampling rate {} Hz or t0 {} s cannot be written", record.fs, record.t0)));
  }
  const Eigen::Index n = record.size();
  for (const Channel& ch : record.channels) {
    if (ch.samples.size() != n) {
      throw InputError(where(name, 0,
                             fmt::format("channel '{}' has {} samples, channel '{}' {}", ch.name,
                                         ch.samples.size(), record.channels[0].name, n)));
    }
  }
}

}  // namespace jointlab::data

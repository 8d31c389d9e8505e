// The uniform in-memory test record every reader produces.
//
// A record is one hit: named channels sampled on one uniform time base
// t_k = t0 + k / fs. Samples are SI (see core/units.h); a channel whose file
// gave no unit has no quantity yet, and the caller decides (--quantity).
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "jointlab/core/units.h"

namespace jointlab::data {

/// One named channel: SI samples and what they measure.
struct Channel {
  std::string name;                  ///< header name without the unit ("acc1")
  std::optional<Quantity> quantity;  ///< from the unit; empty when the file gave none
  std::string unit;                  ///< unit as written in the file ("g"), empty if none
  Eigen::VectorXd samples;           ///< SI values
};

/// One hit: channels on a uniform time base, plus the file's metadata.
struct Record {
  std::string source;                           ///< file the record came from
  double fs = 0.0;                              ///< sample rate [Hz]
  double t0 = 0.0;                              ///< time of the first sample [s]
  std::vector<Channel> channels;                ///< in file order
  std::map<std::string, std::string> metadata;  ///< "# key: value" lines

  /// Number of samples per channel (0 if no channel).
  Eigen::Index size() const { return channels.empty() ? 0 : channels.front().samples.size(); }
  /// The channel with this name, or nullptr.
  const Channel* find(const std::string& name) const;
};

/// Throws InputError naming `name` unless a writer can represent the record: at least one
/// channel, a finite positive sampling rate, a finite t0, every channel equally long.
void check_writable(const Record& record, const std::string& name);

}  // namespace jointlab::data

#include "jointlab/campaign/steps/update_settings.h"

#include <cmath>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::campaign {

void UpdateSettings::fail(const std::string& key, const CampaignSetting& s,
                          const std::string& what) const {
  throw InputError(where(c_.file.string(), s.line, fmt::format("{}.{} {}", table_, key, what)));
}

void UpdateSettings::unknown(const std::string& key, const CampaignSetting& s,
                             const std::string& known) const {
  throw InputError(where(c_.file.string(), s.line,
                         fmt::format("{}: unknown setting '{}' (known: {})", table_, key, known)));
}

double UpdateSettings::number(const std::string& key, const CampaignSetting& s) const {
  const double* v = std::get_if<double>(&s.value);
  if (!v) fail(key, s, "must be a number");
  return *v;
}

int UpdateSettings::whole(const std::string& key, const CampaignSetting& s, int lo, int hi) const {
  const double v = number(key, s);
  if (v != std::floor(v) || v < lo || v > hi)
    fail(key, s, fmt::format("must be a whole number from {} to {}", lo, hi));
  return static_cast<int>(v);
}

bool UpdateSettings::flag(const std::string& key, const CampaignSetting& s) const {
  const bool* v = std::get_if<bool>(&s.value);
  if (!v) fail(key, s, "must be true or false");
  return *v;
}

const std::string& UpdateSettings::text(const std::string& key, const CampaignSetting& s) const {
  const std::string* v = std::get_if<std::string>(&s.value);
  if (!v) fail(key, s, "must be a string");
  return *v;
}

const std::vector<SetBounds>& UpdateSettings::bounds(const std::string& key,
                                                     const CampaignSetting& s) const {
  const auto* v = std::get_if<std::vector<SetBounds>>(&s.value);
  if (!v) fail(key, s, "must be a table of bounds: { \"<set>\" = [lower, upper], ... }");
  return *v;
}

}  // namespace jointlab::campaign

// Typed reading of the settings of an [update.*] table of a campaign file.
#pragma once

#include <string>
#include <vector>

#include "jointlab/campaign/campaign.h"

namespace jointlab::campaign {

/// Reads the settings of one update table by type; every error names the campaign file, the
/// setting's line and its field ("update.linear.rule must be ...").
class UpdateSettings {
 public:
  /// Reader of the table `table` ("update.linear") of campaign `c`.
  UpdateSettings(const Campaign& c, std::string table) : c_(c), table_(std::move(table)) {}
  /// A number.
  double number(const std::string& key, const CampaignSetting& s) const;
  /// A whole number in [lo, hi].
  int whole(const std::string& key, const CampaignSetting& s, int lo, int hi) const;
  /// A flag (true or false).
  bool flag(const std::string& key, const CampaignSetting& s) const;
  /// A text.
  const std::string& text(const std::string& key, const CampaignSetting& s) const;
  /// Bounds of named sets.
  const std::vector<SetBounds>& bounds(const std::string& key, const CampaignSetting& s) const;
  /// Throws InputError "<file>:<line>: <table>.<key>: <what>".
  [[noreturn]] void fail(const std::string& key, const CampaignSetting& s,
                         const std::string& what) const;
  /// Throws InputError for a key the table does not know, listing the known ones.
  [[noreturn]] void unknown(const std::string& key, const CampaignSetting& s,
                            const std::string& known) const;

 private:
  const Campaign& c_;
  std::string table_;
};

}  // namespace jointlab::campaign

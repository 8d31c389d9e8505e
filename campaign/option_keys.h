// The campaign-file keys that stand for the command-line options (docs/campaign-file.md).
//
// The libraries' advice names the options a command-line user types ("run again with a larger
// --evaluations"); inside `run` the same settings are campaign-file keys ("max_evaluations in
// [update.iwan]"). The report says the key, not the option: one mapping here rewrites advice
// text, the libraries' messages stay as the commands print them. An option `run` has no key for
// is named as the command's option with what `run` does instead.
#pragma once

#include <string>

namespace jointlab::campaign {

/// `text` with every command-line option it names ("--mac-threshold", "--hold NAME=VALUE")
/// replaced by the campaign-file key that sets it ("mac_threshold in [update.linear]"), or,
/// where the campaign has none, by what a campaign does instead. Other text is left as it is.
std::string with_campaign_keys(const std::string& text);

}  // namespace jointlab::campaign

#include "jointlab/campaign/option_keys.h"

#include <regex>
#include <string>
#include <utility>
#include <vector>

namespace jointlab::campaign {

namespace {

// One option and what stands for it in a campaign; `option` is a regular expression of the
// option and its argument as the messages write it, `key` the replacement ($1: a captured name).
struct OptionKey {
  const char* option;
  const char* key;
};

// Longer spellings first: "--linear-damping-max" before "--linear-damping".
const std::vector<OptionKey>& option_keys() {
  static const std::vector<OptionKey> keys{
      // update-linear
      {R"(--trust-signs \(a campaign's update\.linear trust_signs = true\))",
       "trust_signs = true in [update.linear]"},
      {"--trust-signs", "trust_signs = true in [update.linear]"},
      {R"(--hold ([A-Za-z0-9_.:]+)(=VALUE)?)",
       "$1 left out of [update.linear] sets, at a value written in the model file"},
      {"--hold", "a set left out of [update.linear] sets, at a value written in the model file"},
      {"--mac-threshold", "mac_threshold in [update.linear]"},
      {"--frequency-window", "frequency_window in [update.linear]"},
      {"--frequency-std", "frequency_std in [update.linear]"},
      {"--alias-mac", "alias_mac in [update.linear]"},
      {"--tolerance", "tolerance in [update.linear]"},
      {"--minimize", "smallest_set in [update.linear]"},
      {"--rule", "rule in [update.linear]"},
      {"--bound-factors", "lower_factor and upper_factor in [update.linear]"},
      {"--bound", "bounds in [update.linear]"},
      // update-iwan
      {"--evaluations", "max_evaluations in [update.iwan]"},
      {"--gamma", "gamma in [update.iwan]"},
      {"--beta", "beta in [update.iwan]"},
      {"--compare", "compare in [update.iwan]"},
      {"--linear-damping-max", "linear_damping_max in [update.iwan]"},
      {"--linear-damping (fit|hold)", "linear_damping = \"$1\" in [update.iwan]"},
      {"--linear-damping", "linear_damping in [update.iwan]"},
      {"--seed", "seed in [update.iwan]"},
      {"--optimizer global-local", "the global-local optimiser (run's own)"},
      {"--optimizer", "update-iwan's optimiser (run uses global-local)"},
      {"--mode", "model_mode of the [[mode]]"},
      {"--dof", "dof of the [[channel]]"},
      // process
      {"--band LO:HI", "band = [LO, HI] of the [[mode]]"},
      {"--band", "band of the [[mode]]"},
      {"--quantity", "quantity in [campaign]"},
      {"--amplitude", "amplitude in [campaign]"},
      {"--max-damping-std", "process's --max-damping-std, which run keeps at its default"},
      {"--min-share", "process's --min-share, which run keeps at its default"},
  };
  return keys;
}

}  // namespace

std::string with_campaign_keys(const std::string& text) {
  if (text.find("--") == std::string::npos) return text;
  // Compiled once: the report calls this on every paragraph and cell. An option starts a word
  // (not "a--b") and ends one (not "--bound" in "--bound-factors"); the character before it is
  // capture 1 and kept, so the key's own captures move up by one ("$1" becomes "$2").
  static const std::vector<std::pair<std::regex, std::string>> compiled = [] {
    std::vector<std::pair<std::regex, std::string>> out;
    for (const OptionKey& k : option_keys()) {
      std::string with = "$1";
      for (const char* c = k.key; *c; ++c) {
        with += *c;
        if (*c == '$' && c[1] >= '1' && c[1] <= '8') with += static_cast<char>(*++c + 1);
      }
      out.emplace_back(std::regex(std::string("(^|[^A-Za-z0-9_-])") + k.option + "(?![A-Za-z-])"),
                       std::move(with));
    }
    return out;
  }();
  std::string out = text;
  for (const auto& [option, key] : compiled) {
    if (out.find("--") == std::string::npos) break;
    out = std::regex_replace(out, option, key);
  }
  return out;
}

}  // namespace jointlab::campaign

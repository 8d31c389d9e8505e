#include "jointlab/campaign/option_keys.h"

#include <string>

#include <gtest/gtest.h>

namespace jointlab::campaign {
namespace {

// The libraries' advice as the commands print it, and as the campaign report says it.
TEST(OptionKeys, AdviceNamesTheCampaignKeys) {
  EXPECT_EQ(with_campaign_keys("run again with a larger --evaluations (e.g. 3000)"),
            "run again with a larger max_evaluations in [update.iwan] (e.g. 3000)");
  EXPECT_EQ(with_campaign_keys("pairs below this MAC (--mac-threshold) are not made"),
            "pairs below this MAC (mac_threshold in [update.linear]) are not made");
  EXPECT_EQ(with_campaign_keys("hold Kt (--gamma, or hold beta with --beta"),
            "hold Kt (gamma in [update.iwan], or hold beta with beta in [update.iwan]");
  // An option with its argument: the set named is kept.
  EXPECT_EQ(with_campaign_keys("hold it elsewhere with --hold spring.kr=VALUE"),
            "hold it elsewhere with spring.kr left out of [update.linear] sets, at a value "
            "written in the model file");
  // The longer option is not taken for the shorter one.
  EXPECT_EQ(with_campaign_keys("--bound-factors and --bound and --linear-damping-max"),
            "lower_factor and upper_factor in [update.linear] and bounds in [update.linear] and "
            "linear_damping_max in [update.iwan]");
  // An option with its value: the key with that value.
  EXPECT_EQ(with_campaign_keys("fit it with --linear-damping fit (or set [damping] modal_ratio"),
            "fit it with linear_damping = \"fit\" in [update.iwan] (or set [damping] modal_ratio");
  // The messages that already name the campaign's key say it once.
  EXPECT_EQ(with_campaign_keys("fit them with --trust-signs (a campaign's update.linear "
                               "trust_signs = true)"),
            "fit them with trust_signs = true in [update.linear]");
  // An option run has no key for says so.
  EXPECT_EQ(with_campaign_keys("the 5.0 % limit (--max-damping-std)"),
            "the 5.0 % limit (process's --max-damping-std, which run keeps at its default)");
}

// Text that names no option, or only looks like one, is left as it is.
TEST(OptionKeys, OtherTextIsLeftAsItIs) {
  for (const std::string& t :
       {std::string("no option here"), std::string("a--gamma b"), std::string("x --gammas y"),
        std::string("file hit--1.csv"), std::string("-- a dash")}) {
    EXPECT_EQ(with_campaign_keys(t), t);
  }
}

}  // namespace
}  // namespace jointlab::campaign

#include "jointlab/core/rank_correlation.h"

#include <cstddef>
#include <vector>

#include <gtest/gtest.h>

namespace jointlab {
namespace {

// Reference values from scipy 1.10.1, printed once by
//   python3 -c "from scipy.stats import spearmanr; print(repr(spearmanr(a, b).correlation))"
// for the samples below. Tolerance 1e-14 absolute: the ranks are exact small integers, so the
// two computations differ only in the rounding of a few sums and one division or square root
// (a few units of 1e-16).
constexpr double kRounding = 1e-14;

TEST(RankCorrelation, MatchesScipysSpearmanWithoutTies) {
  const std::vector<double> a = {3.1, 0.5, 2.2, 4.8, 1.7, 5.9, 0.2};
  const std::vector<double> b = {2.0, 1.1, 3.5, 4.4, 0.9, 6.1, 1.8};
  EXPECT_NEAR(rank_correlation(a, b), 0.8214285714285715, kRounding);  // 23/28
  EXPECT_NEAR(rank_correlation(b, a), 0.8214285714285715, kRounding);
  EXPECT_DOUBLE_EQ(rank_correlation(a, a), 1.0);
}

TEST(RankCorrelation, TrendIsTheCorrelationWithTheIndex) {
  const std::vector<double> x = {0.9, 0.7, 0.8, 0.5, 0.6, 0.3, 0.4, 0.1};
  std::vector<double> index(x.size());
  for (size_t i = 0; i < x.size(); ++i) index[i] = static_cast<double>(i);
  // scipy's spearmanr(x, range(8)): -13/14.
  EXPECT_NEAR(rank_trend(x), -0.9285714285714287, kRounding);
  EXPECT_NEAR(rank_correlation(x, index), -0.9285714285714287, kRounding);
  EXPECT_DOUBLE_EQ(rank_trend({1.0, 2.0, 3.0, 4.0}), 1.0);
  EXPECT_DOUBLE_EQ(rank_trend({4.0, 3.0, 2.0, 1.0}), -1.0);
}

// Equal values are ranked in the order given, not given their mean rank as scipy does: the
// statistic is scipy's for the same values with each tie broken upwards in order (1, 1.001,
// 1.002), not scipy's for the tied values themselves (0.6708 and -0.2236 there).
TEST(RankCorrelation, TiesAreRankedInTheOrderGiven) {
  const std::vector<double> tied = {1.0, 1.0, 2.0, 0.0, 1.0};
  EXPECT_EQ(ranks(tied), (std::vector<double>{1.0, 2.0, 4.0, 0.0, 3.0}));
  const std::vector<double> c = {5.0, 3.0, 4.0, 1.0, 2.0};
  EXPECT_NEAR(rank_correlation(tied, c), 0.3, kRounding);  // spearmanr(tie-broken, c)
  EXPECT_NEAR(rank_trend(tied), 0.2, kRounding);           // spearmanr(tie-broken, range(5))
}

}  // namespace
}  // namespace jointlab

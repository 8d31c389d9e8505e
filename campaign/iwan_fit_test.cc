#include "jointlab/campaign/iwan_fit.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/two_chain.h"

namespace jointlab::campaign {
namespace {

using correlate::IwanObjective;
using correlate::IwanUpdateOptions;

// One mode held by an Iwan joint alone (correlate::one_mode_structure with no parallel spring:
// F_S 20 N, K_T 1e5 N/m, 49.5 Hz at low amplitude); ring-down backbones at its DOF.
struct Hits {
  model::IwanParameters truth{20, 1e5, -0.5, 1};
  model::Model m = correlate::one_mode_structure(0, truth);
  std::vector<correlate::Sensor> sensors{{"x", 0, 1.0}};
  correlate::IwanTarget target;
  Hits() {
    target.mode = 1;
    target.curves.push_back(correlate::synthetic_backbone(
        m, 1, sensors, 0, correlate::AmplitudeQuantity::kVelocity, 12, 0.9, 5e-4, 0.03, 7));
  }
};

// The message of the InputError `f` throws, or "" when it throws none.
template <typename F>
std::string refusal(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Each range outside its parameter's domain is refused naming the option, as the command line
// and the Python module both say it; absent ranges leave the default box.
TEST(IwanRanges, RefusesARangeOutsideItsDomainAndDefaultsTheRest) {
  EXPECT_EQ(refusal([] {
              IwanRanges{.chi = {{-1, 0.5}}}.check();
            }),
            "--chi-range -1:0.5: need LO < HI with both chi > -1");
  // chi above 0 is in the domain (method.md: -1 < chi): a range reaching past 0 is the user's.
  EXPECT_EQ(refusal([] { IwanRanges{.chi = {{0.1, 0.5}}}.check(); }), "");
  const IwanRanges wide{.chi = {{-0.9, 0.9}}};
  EXPECT_EQ(wide.bounds({40, 1e6, 0.3, 1}).chi_max, 0.9);
  EXPECT_EQ(refusal([] {
              IwanRanges{.fs = {{2000, 1000}}}.check();
            }),
            "--fs-range 2000:1000: need LO < HI with both Fs > 0");
  EXPECT_NE(refusal([] {
              IwanRanges{.beta = {{0, 5}}}.check();
            }).find("need 0 < LO < HI (beta is searched on a log scale)"),
            std::string::npos);
  EXPECT_EQ(refusal([] { IwanRanges{}.check(); }), "");
  model::IwanParameters start{20, 5e5, -0.5, 1};
  const correlate::IwanBounds d = correlate::default_iwan_bounds(start);
  const correlate::IwanBounds b = IwanRanges{.gamma = {{0.5, 1.5}}}.bounds(start);
  EXPECT_EQ(b.Fs_min, d.Fs_min);
  EXPECT_EQ(b.Fs_max, d.Fs_max);
  EXPECT_EQ(b.gamma_min, 0.5);
  EXPECT_EQ(b.gamma_max, 1.5);
  EXPECT_EQ(b.chi_min, d.chi_min);
  EXPECT_EQ(b.beta_max, d.beta_max);
  // The default chi range -0.95:0 holds the start: a model of chi 0.3 or -0.98 (chi > -1 is
  // the element's domain) is searched from where it is (before: from a box that missed it).
  EXPECT_EQ(d.chi_min, -0.95);
  EXPECT_EQ(d.chi_max, 0.0);
  EXPECT_EQ(correlate::default_iwan_bounds({20, 5e5, 0.3, 1}).chi_max, 0.3);
  EXPECT_EQ(correlate::default_iwan_bounds({20, 5e5, 0.3, 1}).chi_min, -0.95);
  EXPECT_EQ(correlate::default_iwan_bounds({20, 5e5, -0.98, 1}).chi_min, -0.98);
  const IwanRanges given{.chi = {{-0.5, 0.1}}};  // a range given is taken as given
  EXPECT_EQ(given.bounds({20, 5e5, 0.3, 1}).chi_max, 0.1);
}

// K_T held to a tenth of K_s at most: the measured 49.5 Hz is out of reach (K_T = K_s gives
// it), which is said with the command's and the data's names before any fit; with gamma up
// to 2 the fit is made.
TEST(CheckedFitIwan, FrequenciesOutOfTheBoxsReachAreRefusedBeforeAnyFit) {
  const Hits h;
  const IwanObjective objective(h.m, "iwan.j", h.sensors, {h.target}, {});
  IwanUpdateOptions o;
  o.samples = 20;
  o.max_evaluations = 40;
  const std::string why = refusal([&] {
    checked_fit_iwan(objective, o, IwanRanges{.gamma = {{0.05, 0.1}}}, "update.iwan", "hits",
                     nullptr);
  });
  EXPECT_TRUE(why.starts_with("update.iwan: hits: ")) << why;
  EXPECT_EQ(refusal([&] {
              checked_fit_iwan(objective, o, IwanRanges{.gamma = {{0.05, 2}}}, "update.iwan",
                               "hits", nullptr);
            }),
            "");
}

// The progress line comes at the first evaluation at or past each multiple of 250: the local
// solves' count steps over multiples (a 423-evaluation fit of the one-mode model, counted
// 1, ..., 248, 253, 259, ...: no line at all where the test was n % 250 == 0); a second fit
// counting from 1 again gets its own lines; the evaluations between call `between`.
TEST(ProgressEvery, ALineAtTheFirstEvaluationPastEachMultiple) {
  std::vector<int> lines;
  int between = 0;
  const auto progress = progress_every(
      250, [&](int n, double) { lines.push_back(n); }, [&] { ++between; });
  for (int n : {1, 2, 248, 253, 259, 499, 506, 750, 3, 251}) progress(n, 1.0);
  EXPECT_EQ(lines, (std::vector<int>{253, 506, 750, 251}));
  EXPECT_EQ(between, 6);
}

}  // namespace
}  // namespace jointlab::campaign

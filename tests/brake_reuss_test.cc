// Issue 2 acceptance on measured data: the Brake-Reuss beam hammer record in
// data/examples/brake-reuss-beam/ (first mode near 80.5 Hz, three channels).
// acc1 and acc3 must give backbones spanning a decade that agree at the same
// instants (frequency within 0.02 %, damping within 5 %); acc2 barely sees the
// mode, so whatever it reports must agree with acc1 within its own stated
// uncertainty (or it may refuse or keep a short span).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/data/read_record.h"
#include "jointlab/modal/process.h"
#include "jointlab/tests/test_util.h"

namespace jointlab {
namespace {

// Linear interpolation of column y(t) at time t (t inside the range).
double at(const Eigen::VectorXd& time, const Eigen::VectorXd& y, double t) {
  Eigen::Index i = 1;
  while (i < time.size() - 1 && time(i) < t) ++i;
  const double w = (t - time(i - 1)) / (time(i) - time(i - 1));
  return (1 - w) * y(i - 1) + w * y(i);
}

TEST(BrakeReuss, ChannelsAgreeOnTheFirstModeBackbone) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  modal::ProcessOptions opt;
  opt.bands = {{70, 90}};
  signal::FftCache cache;
  const modal::RecordResult res = modal::process_record(rec, opt, cache);
  ASSERT_EQ(res.results.size(), 3u);
  const modal::Ringdown& r1 = res.results[0].ringdown;
  const modal::Ringdown& r2 = res.results[1].ringdown;
  const modal::Ringdown& r3 = res.results[2].ringdown;
  ASSERT_EQ(r1.summary.status, modal::RingdownStatus::kOk) << r1.summary.message;
  ASSERT_EQ(r3.summary.status, modal::RingdownStatus::kOk) << r3.summary.message;
  EXPECT_GE(r1.summary.amplitude_decades, 1.0);
  EXPECT_GE(r3.summary.amplitude_decades, 1.0);
  // The mode softens and loses damping as it decays (80.4 -> 80.6 Hz).
  EXPECT_NEAR(r1.summary.linear_frequency_hz, 80.58, 0.1);

  const modal::Backbone& b1 = r1.backbone;
  const modal::Backbone& b3 = r3.backbone;
  int compared = 0;
  double worst_f = 0, worst_z = 0;
  for (Eigen::Index i = 0; i < b3.size(); ++i) {
    const double t = b3.time_s(i);
    if (t < b1.time_s(0) || t > b1.time_s(b1.size() - 1)) continue;
    worst_f =
        std::max(worst_f, testing::rel_err(b3.frequency_hz(i), at(b1.time_s, b1.frequency_hz, t)));
    worst_z = std::max(worst_z, testing::rel_err(b3.damping(i), at(b1.time_s, b1.damping, t)));
    ++compared;
  }
  std::printf(
      "acc1 vs acc3: %d instants, worst frequency difference %.2e, worst damping "
      "difference %.4f\n",
      compared, worst_f, worst_z);
  EXPECT_GE(compared, 20);
  EXPECT_LE(worst_f, 2e-4);
  EXPECT_LE(worst_z, 0.05);

  // acc2 sees mode 1 at about 4 % of acc1's amplitude (its spectrum is dominated by the
  // 298 Hz mode): by default it gives no backbone, with the reason, and keeps its shape entry.
  EXPECT_NE(r2.summary.status, modal::RingdownStatus::kOk);
  EXPECT_NE(r2.summary.message.find("% of the strongest channel"), std::string::npos)
      << r2.summary.message;
  EXPECT_EQ(r2.backbone.size(), 0);
  const double share2 = std::abs(res.results[1].complex_amplitude) /
                        std::max(std::abs(res.results[0].complex_amplitude),
                                 std::abs(res.results[2].complex_amplitude));
  std::printf("acc2 sees mode 1 at %.1f %% of the strongest channel\n", 100 * share2);
  EXPECT_GT(share2, 0.01);  // a real, small entry of the operating shape
  EXPECT_LT(share2, 0.1);
}

// Forced to report (--min-share 0), acc2's damping near the impact reads 1-4 % above
// acc1's and acc3's (which agree within 1.1 %), several times its stated uncertainty:
// the confident wrong values the default refusal prevents.
TEST(BrakeReuss, WeakChannelForcedToReportDisagreesNearTheImpact) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  modal::ProcessOptions opt;
  opt.bands = {{70, 90}};
  opt.min_share = 0;
  signal::FftCache cache;
  const modal::RecordResult res = modal::process_record(rec, opt, cache);
  ASSERT_EQ(res.results.size(), 3u);
  const modal::Backbone& b1 = res.results[0].ringdown.backbone;
  const modal::Backbone& b2 = res.results[1].ringdown.backbone;
  ASSERT_GT(b1.size(), 0);
  ASSERT_GT(b2.size(), 0);
  int outside = 0, compared = 0;
  for (Eigen::Index i = 0; i < b2.size(); ++i) {
    const double t = b2.time_s(i);
    if (t < b1.time_s(0) || t > b1.time_s(b1.size() - 1)) continue;
    ++compared;
    const double dz = std::abs(b2.damping(i) - at(b1.time_s, b1.damping, t));
    const double uz = std::hypot(b2.damping_std(i), at(b1.time_s, b1.damping_std, t));
    outside += dz > uz;
  }
  std::printf("acc2 forced: damping outside the combined uncertainty at %d of %d instants\n",
              outside, compared);
  EXPECT_GE(compared, 20);
  EXPECT_GE(outside, 2);
}

// Largest relative difference between two backbones of the same points (infinite if
// their sizes differ).
double backbone_difference(const modal::Backbone& a, const modal::Backbone& b) {
  if (a.size() != b.size() || a.size() == 0) return std::numeric_limits<double>::infinity();
  double worst = 0;
  for (const auto& [x, y] : {std::pair{&a.time_s, &b.time_s},
                             {&a.amplitude, &b.amplitude},
                             {&a.frequency_hz, &b.frequency_hz},
                             {&a.damping, &b.damping},
                             {&a.damping_std, &b.damping_std}}) {
    worst = std::max(worst, ((*x - *y).array().abs() / y->array().abs()).maxCoeff());
  }
  return worst;
}

const modal::ChannelBand& result_of(const modal::RecordResult& res, const std::string& channel,
                                    int band) {
  for (const modal::ChannelBand& r : res.results) {
    if (r.channel == channel && r.band_index == band) return r;
  }
  throw std::runtime_error("no result for " + channel);
}

// A band's backbone depends on that band, channel and file alone: acc1 in 70:90 Hz is
// the same (relative 1e-9) with the 280:315 Hz band requested beside it, and acc3's
// results are the same when acc1 carries a corrupted sample (1e300) and is processed
// with it.
TEST(BrakeReuss, EachBandAndChannelStandsAlone) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  signal::FftCache cache;
  modal::ProcessOptions one;
  one.bands = {{70, 90}};
  const modal::RecordResult alone = modal::process_record(rec, one, cache);
  modal::ProcessOptions two = one;
  two.bands.push_back({280, 315});
  const modal::RecordResult both = modal::process_record(rec, two, cache);
  const modal::Backbone& a1 = result_of(alone, "acc1", 1).ringdown.backbone;
  const modal::Backbone& b1 = result_of(both, "acc1", 1).ringdown.backbone;
  std::printf("acc1 70:90: %ld rows alone, %ld with 280:315 beside it\n", long(a1.size()),
              long(b1.size()));
  ASSERT_GT(a1.size(), 20);
  EXPECT_LE(backbone_difference(a1, b1), 1e-9);

  for (const Eigen::Index where : {Eigen::Index{200}, rec.size() / 2}) {
    data::Record bad = rec;
    bad.channels[0].samples(where) = 1e300;
    const modal::RecordResult res = modal::process_record(bad, one, cache);
    const modal::ChannelBand& r3 = result_of(res, "acc3", 1);
    const modal::ChannelBand& ok3 = result_of(alone, "acc3", 1);
    ASSERT_EQ(r3.ringdown.summary.status, modal::RingdownStatus::kOk)
        << r3.ringdown.summary.message;
    EXPECT_LE(backbone_difference(r3.ringdown.backbone, ok3.ringdown.backbone), 1e-9)
        << "1e300 at sample " << where;
    EXPECT_EQ(result_of(res, "acc2", 1).ringdown.summary.status, modal::RingdownStatus::kNoSpan);
  }
}

// A band says which mode (issue 26): typed with the mode on its sloping edge, 79:99 Hz (the
// mode at 80.3-80.6 Hz, 1.3 Hz above the edge, below the half-gain point 81.5 Hz) or 72:82
// Hz (on the upper edge), the measured mode is read through a band that follows it and
// must agree with the centred band 70:90 Hz at the same instants: median frequency within
// 2e-5 and median damping within 1 %, over at least 1.4 decades for 79:99 (the centred band
// keeps 1.70 and 1.76) and 1.0 for 72:82. Before the band followed the mode, 79:99 gave no
// backbone on either channel and 72:82 kept acc3 from 1.0 s (median errors then 2.5e-6 and
// 0.1 %). Measured now: 1.71/1.77 decades (72:82: 1.63/1.70), median differences at most
// 1.4e-6 and 0.1 %.
// The record's own spectrum has no peak from 65 to 90 Hz but the mode's (80.47 Hz): no band
// may be held back by a neighbouring mode there. acc3's 72:82 Hz band once was, by a peak at
// 75.34 Hz of its backward continuation alone, and kept 1.53 decades instead of 1.68.
TEST(BrakeReuss, AModeOnItsBandsEdgeReadsAsInTheCentredBand) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  signal::FftCache cache;
  modal::ProcessOptions centred;
  centred.bands = {{70, 90}};
  const modal::RecordResult ref = modal::process_record(rec, centred, cache);
  for (const signal::Band band : {signal::Band{79, 99}, signal::Band{72, 82}}) {
    modal::ProcessOptions edge;
    edge.bands = {band};
    const modal::RecordResult res = modal::process_record(rec, edge, cache);
    for (const char* channel : {"acc1", "acc3"}) {
      const modal::Ringdown& r = result_of(res, channel, 1).ringdown;
      ASSERT_EQ(r.summary.status, modal::RingdownStatus::kOk) << r.summary.message;
      const modal::Backbone& b = r.backbone;
      const modal::Backbone& c = result_of(ref, channel, 1).ringdown.backbone;
      std::vector<double> ef, ez;
      for (Eigen::Index i = 0; i < b.size(); ++i) {
        const double t = b.time_s(i);
        if (t < c.time_s(0) || t > c.time_s(c.size() - 1)) continue;
        ef.push_back(testing::rel_err(b.frequency_hz(i), at(c.time_s, c.frequency_hz, t)));
        ez.push_back(testing::rel_err(b.damping(i), at(c.time_s, c.damping, t)));
      }
      ASSERT_GE(ef.size(), 10u) << channel;
      std::sort(ef.begin(), ef.end());
      std::sort(ez.begin(), ez.end());
      std::printf("%s in %g:%g Hz: %.2f decades, median differences %.1e and %.4f; %s\n", channel,
                  band.lo, band.hi, r.summary.amplitude_decades, ef[ef.size() / 2],
                  ez[ez.size() / 2], r.summary.message.c_str());
      EXPECT_GE(r.summary.amplitude_decades, band.lo == 79 ? 1.4 : 1.0) << channel;
      EXPECT_EQ(r.summary.message.find("neighbouring mode"), std::string::npos) << channel;
      EXPECT_LE(ef[ef.size() / 2], 2e-5) << channel;
      EXPECT_LE(ez[ez.size() / 2], 0.01) << channel;
    }
  }
}

// A band beside the mode (81:99 Hz, the mode at 80.4 Hz outside its half-gain points; 298:320
// Hz, the mode at 297.7 Hz) gives no backbone, and each reason is its own clause: the spectral
// advice and the count of points the band passes too weakly once ran together ("... 96.75 Hz20
// points left out ..."). In 298:320 Hz the filter's skirt passes the mode well enough for
// every channel's points to be read, and the band followed it: all three had that mode's
// backbone; now each says where the mode lies, outside the typed band.
TEST(BrakeReuss, ABandBesideTheModeSaysEachReasonApart) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  signal::FftCache cache;
  modal::ProcessOptions opt;
  opt.bands = {{81, 99}, {298, 320}};
  const modal::RecordResult res = modal::process_record(rec, opt, cache);
  int advised = 0;
  for (const modal::ChannelBand& r : res.results) {
    const std::string& m = r.ringdown.summary.message;
    SCOPED_TRACE(r.channel + ": " + m);
    EXPECT_NE(r.ringdown.summary.status, modal::RingdownStatus::kOk);
    if (r.band_index == 2) {
      EXPECT_NE(m.find("no mode in the band: the mode its filter passes lies at 297."),
                std::string::npos);
      EXPECT_NE(m.find("outside the typed band 298:320 Hz"), std::string::npos);
      continue;
    }
    if (m.find("no mode in the band") == std::string::npos) continue;
    ++advised;
    const size_t weak = m.find("points left out where the band passes less than half");
    if (weak == std::string::npos) continue;
    // "; <count> points left out": the clause starts after a separator.
    const size_t start = m.rfind("; ", weak);
    ASSERT_NE(start, std::string::npos);
    EXPECT_TRUE(std::all_of(m.begin() + static_cast<long>(start) + 2,
                            m.begin() + static_cast<long>(weak) - 1,
                            [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }));
  }
  EXPECT_GE(advised, 2);
}

// --modes 3 on the measured record: its three most prominent peaks (80.5, 297.7 and 1527 Hz)
// are modes, so no peak is left out and the bands are those of the three peaks, as before
// peaks were checked; --modes 7 reaches the harmonic (161 Hz), a leakage peak beside
// 297.7 Hz (221.7 Hz) and others, which are left out with their reasons: every band the
// program keeps has linear values at its reference channel.
TEST(BrakeReuss, ModesChooseOnlyBandsTheyProcess) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  signal::FftCache cache;
  std::vector<const data::Channel*> chans;
  for (const data::Channel& c : rec.channels) chans.push_back(&c);
  for (const int n : {3, 7}) {
    SCOPED_TRACE(n);
    modal::ProcessOptions opt;
    opt.modes = n;
    const modal::RecordResult res = modal::process_record(rec, opt, cache);
    for (size_t b = 0; b < res.bands.size(); ++b)
      EXPECT_EQ(modal::band_refusal(res, static_cast<int>(b) + 1), "") << b + 1;
    if (n == 3) {
      EXPECT_TRUE(res.left_out.empty());
      EXPECT_TRUE(res.shortfall.empty());
      const std::vector<signal::Band> peaks = modal::bands_from_peaks(rec, chans, 3, cache);
      ASSERT_EQ(res.bands.size(), peaks.size());
      for (size_t b = 0; b < peaks.size(); ++b) {
        EXPECT_EQ(res.bands[b].lo, peaks[b].lo);
        EXPECT_EQ(res.bands[b].hi, peaks[b].hi);
      }
    } else {
      EXPECT_FALSE(res.left_out.empty());
      for (const modal::LeftOutPeak& p : res.left_out) EXPECT_FALSE(p.reason.empty());
    }
  }
}

// The measured record's 1527 Hz mode is amplitude-modulated by the 80.5 Hz mode: its band
// (1297.7:1755.8 Hz with --modes 3) shows peaks at 1447 and 1607 Hz, 80 Hz either side, and
// the 297.7 Hz band shows the 80.5 Hz mode's fourth harmonic at 322 Hz. Neither is a second
// mode: read as one, acc1 and acc3's linear damping of the 1527 Hz mode moved 8.5e-5 apart
// against a combined expanded uncertainty of 2.4e-5 (4.0e-5 against 1.25e-5 before second
// modes were looked for), and acc2's 297.7 Hz span lost 0.044 s. No band's note names one.
TEST(BrakeReuss, SidebandsAndHarmonicsAreNoSecondModes) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  signal::FftCache cache;
  modal::ProcessOptions opt;
  opt.modes = 3;
  const modal::RecordResult res = modal::process_record(rec, opt, cache);
  ASSERT_EQ(res.bands.size(), 3u);
  for (const modal::ChannelBand& r : res.results) {
    EXPECT_EQ(r.ringdown.summary.message.find("second mode"), std::string::npos)
        << r.channel << " band " << r.band_index << ": " << r.ringdown.summary.message;
  }
}

// A drifting mode's own rest is no neighbour's beat. Typed 80:115 or 79.5:114.5 Hz, the 80.5 Hz
// mode runs 0.2-0.5 Hz inside the lower edge and the band moves down past it (read through
// 70.86:105.86 Hz). On acc2 (the channel near the node, read here with --min-share 0) what a
// quadratic leaves of ln A + i theta over two beats from the span's start passed the edge-beat
// rule's checks as a second mode 0.7 Hz below (c 0.18, the other turn c / 11.2-11.5, 2.8 % of
// the rest left): 14 points that met the damping limit were left out, the span started at
// 0.90 s and kept 1.20 decades, where the same band read without it starts at 0.115 s and
// keeps 1.59. Fitted again a quarter and half a beat later the "beat" is 4.6-4.7 times what
// the first fit carried there (the 259 true neighbours caught on the LMS twins stay within 0.36 of
// it), so it no longer counts. Required: no note of a second mode beyond the edge, and 1.4 decades
// (between the 1.20 with the false beat and the 1.59 without it).
TEST(BrakeReuss, ADriftingModesOwnRestIsNoBeatBeyondTheEdge) {
  const data::Record rec = data::read_record(testing::source_dir() +
                                             "/data/examples/brake-reuss-beam/hammer_impact.csv");
  signal::FftCache cache;
  for (const signal::Band band : {signal::Band{80, 115}, signal::Band{79.5, 114.5}}) {
    modal::ProcessOptions opt;
    opt.bands = {band};
    opt.channels = {"acc2"};
    opt.min_share = 0;
    const modal::RecordResult res = modal::process_record(rec, opt, cache);
    const modal::Ringdown& r = result_of(res, "acc2", 1).ringdown;
    std::printf("acc2 in %g:%g Hz: %.2f decades from %.3f s; %s\n", band.lo, band.hi,
                r.summary.amplitude_decades, r.summary.span_start_s, r.summary.message.c_str());
    ASSERT_EQ(r.summary.status, modal::RingdownStatus::kOk) << r.summary.message;
    EXPECT_EQ(r.summary.message.find("takes in a second mode"), std::string::npos)
        << r.summary.message;
    EXPECT_GE(r.summary.amplitude_decades, 1.4) << r.summary.message;
  }
}

}  // namespace
}  // namespace jointlab

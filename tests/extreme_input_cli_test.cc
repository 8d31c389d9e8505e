// `jointlab process` on records that are well formed but absurd in size: a sample rate of
// 1e300 Hz written by the UFF 58 and MAT writers (dt = 1e-300 once overflowed a cast and
// crashed the command), and a 2-row CSV with 200 000 channels (once quadratic in channels).
// Each is refused with one line naming the file and what is wrong, exit status 2.
#include <cmath>
#include <filesystem>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/data/mat_file.h"
#include "jointlab/data/record.h"
#include "jointlab/data/uff58.h"
#include "jointlab/tests/cli.h"

namespace jointlab::testing {
namespace {

void expect_one_line(const CommandResult& r, const std::string& says) {
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
}

TEST(ExtremeInput, SampleRateOf1e300FromUffAndMatIsRefused) {
  const std::string dir = scratch_dir("extreme_rate");
  data::Record rec;
  rec.fs = 1e300;
  data::Channel ch;
  ch.name = "acc1";
  ch.quantity = Quantity::kAcceleration;
  ch.unit = "m/s^2";
  ch.samples.resize(4000);
  for (int k = 0; k < 4000; ++k) ch.samples(k) = std::exp(-1e-3 * k) * std::sin(0.3 * k);
  rec.channels.push_back(ch);
  const std::string uff = dir + "/fast.uff", mat = dir + "/fast.mat";
  data::write_uff58(uff, rec, false);
  data::write_mat(mat, rec);
  for (const std::string& file : {uff, mat}) {
    const CommandResult r = run_jointlab("process " + file + " --band 70:90 --out " + dir + "/o");
    expect_one_line(r, file + ": sample rate 1e+300 Hz");
    EXPECT_FALSE(std::filesystem::exists(dir + "/o/summary.json")) << file;
  }
}

TEST(ExtremeInput, TwoRowsOf200000ChannelsAreRefusedQuickly) {
  const std::string dir = scratch_dir("extreme_wide");
  std::string header = "time", row0 = "0", row1 = "0.001";
  for (int c = 0; c < 200000; ++c) {
    header += fmt::format(",c{} [m/s^2]", c);
    row0 += ",0";
    row1 += ",1";
  }
  write_text(dir + "/wide.csv", header + "\n" + row0 + "\n" + row1 + "\n");
  const CommandResult r =
      run_jointlab("process " + dir + "/wide.csv --band 70:90 --out " + dir + "/o");
  expect_one_line(r, "wide.csv: 2 samples: too short for a ring-down");
}

}  // namespace
}  // namespace jointlab::testing

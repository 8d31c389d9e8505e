// Writes the benchmark record and the truth it was made from:
//   RECORD.csv  8 acceleration channels, fs 5120 Hz, 6 s, three modes (60, 162,
//               366 Hz), the first strongly nonlinear, white noise at 0.1 % of
//               each channel's peak (tests/synthetic.h, three_mode_record);
//   TRUTH.csv   the first mode's backbone: displacement amplitude [m], natural
//               frequency [Hz] and damping ratio on a log grid.
// Usage: jointlab_make_bench_record RECORD.csv TRUTH.csv
#include <cmath>
#include <cstdio>
#include <numbers>

#include "jointlab/data/record.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/tests/synthetic.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s RECORD.csv TRUTH.csv\n", argv[0]);
    return 2;
  }
  jointlab::data::Record rec;
  rec.source = argv[1];
  rec.fs = 5120.0;
  rec.metadata["test"] = "benchmark record: three modes, first nonlinear, 0.1 % noise";
  jointlab::testing::SlowFlowMode truth;
  for (int c = 0; c < 8; ++c) {
    const auto r = jointlab::testing::three_mode_record(60.0, 6.0, 1e-3, 100 + c);
    truth = r.first;
    jointlab::data::Channel ch;
    ch.name = "acc" + std::to_string(c + 1);
    ch.quantity = jointlab::Quantity::kAcceleration;
    ch.unit = "m/s^2";
    ch.samples = r.acceleration;
    rec.channels.push_back(ch);
  }
  jointlab::data::write_csv_record(argv[1], rec);
  const int n = 400;
  Eigen::VectorXd a(n), f(n), z(n);
  for (int i = 0; i < n; ++i) {
    a(i) = truth.a0 * std::pow(10.0, -4.0 * i / (n - 1));
    f(i) = truth.omega_n(a(i)) / (2 * std::numbers::pi);
    z(i) = truth.zeta(a(i));
  }
  jointlab::data::Table t;
  t.add("amplitude_m", a);
  t.add("frequency_hz", f);
  t.add("damping_ratio", z);
  jointlab::data::write_table(argv[2], t);
  return 0;
}

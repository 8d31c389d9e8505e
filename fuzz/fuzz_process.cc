// libFuzzer target: `process` end to end on small fuzzed records. The input's first 8 bytes
// choose the record's shape (channels, their quantities, the sample rate, the band, the
// amplitude quantity, the method), the rest are the samples as doubles, channel after
// channel, at most kMaxSamples each (an input with a non-finite sample is skipped: no reader
// returns one). The sample rate is one of four usual rates or, when byte 1 has its high bit
// set, any rate from 1e-300 to 2e300 Hz (bytes 1 and 7), as absurd as a file's time column
// can make it. The
// record is written as a CSV file and read back, processed as `jointlab process` does, and
// its backbones and summary.json are written; anything but that or an InputError is a
// finding.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <vector>

#include "fuzz_util.h"
#include "jointlab/core/error.h"
#include "jointlab/data/read_record.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/modal/process.h"
#include "jointlab/modal/process_output.h"

namespace {

using jointlab::Quantity;

constexpr std::array<Quantity, 4> kQuantities{Quantity::kAcceleration, Quantity::kVelocity,
                                              Quantity::kDisplacement, Quantity::kForce};
constexpr std::array<double, 4> kRates{1000.0, 2048.0, 5120.0, 1e5};
constexpr size_t kMaxSamples = 1024;

// The sample rate bytes 1 and 7 choose: a usual rate, or m 10^e with m in [1, 2) from byte 1's
// low bits and e in [-300, 300] from byte 7.
double sample_rate(const uint8_t* data) {
  if ((data[1] & 0x80) == 0) return kRates[data[1] % kRates.size()];
  return (1 + (data[1] & 0x7f) / 128.0) * std::pow(10.0, -300.0 + 600.0 * data[7] / 255.0);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  namespace fs = std::filesystem;
  if (size < 8) return 0;
  const int channels = 1 + data[0] % 3;
  const double fs_hz = sample_rate(data);
  // Band edges as fractions of Nyquist (the record's own checks judge them).
  const double lo = (1 + data[2]) / 257.0 * fs_hz / 2, hi = lo + (1 + data[3]) / 257.0 * fs_hz / 2;
  const size_t n = std::min(kMaxSamples, (size - 8) / 8 / static_cast<size_t>(channels));
  jointlab::data::Record rec;
  rec.fs = fs_hz;
  for (int c = 0; c < channels; ++c) {
    jointlab::data::Channel ch;
    ch.name = "ch" + std::to_string(c + 1);
    ch.quantity = kQuantities[(data[4] >> (2 * c)) % kQuantities.size()];
    ch.samples.resize(static_cast<Eigen::Index>(n));
    for (size_t k = 0; k < n; ++k) {
      double x = 0;
      std::memcpy(&x, data + 8 + 8 * (static_cast<size_t>(c) * n + k), sizeof x);
      if (!std::isfinite(x)) return 0;
      ch.samples(static_cast<Eigen::Index>(k)) = x;
    }
    rec.channels.push_back(std::move(ch));
  }
  const fs::path dir = jointlab::fuzz::scratch();
  const fs::path file = dir / "hit.csv", out = dir / "out";
  fs::remove_all(out);
  fs::create_directories(out);
  try {
    jointlab::data::write_record(file, rec);
    const jointlab::data::Record read = jointlab::data::read_record(file.string());
    jointlab::modal::ProcessOptions opt;
    opt.bands = {{lo, hi}};
    opt.ringdown.amplitude = kQuantities[data[5] % 3];
    opt.ringdown.method =
        data[6] % 2 ? jointlab::modal::Method::kPeaks : jointlab::modal::Method::kHilbert;
    jointlab::signal::FftCache cache;
    std::vector<jointlab::modal::RecordResult> results{
        jointlab::modal::process_record(read, opt, cache)};
    jointlab::modal::write_backbones(out, results.front(), opt.ringdown);
    jointlab::modal::write_summary(out, results, opt);
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

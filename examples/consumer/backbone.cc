// backbone: the backbone of one channel in one band of a test record, printed as CSV, with
// jointlab used as an installed library (examples/consumer/CMakeLists.txt builds it).
//
//   backbone RECORD CHANNEL LO:HI
//   backbone data/examples/brake-reuss-beam/hammer_impact.csv acc1 70:90
#include <cstdio>
#include <exception>
#include <string>

#include <jointlab/core/error.h>
#include <jointlab/data/read_record.h>
#include <jointlab/modal/process.h>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: backbone RECORD CHANNEL LO:HI\n");
    return 2;
  }
  try {
    const std::string band = argv[3];
    const size_t colon = band.find(':');
    if (colon == std::string::npos) throw jointlab::InputError("band: expected LO:HI in Hz");
    jointlab::modal::ProcessOptions options;
    options.channels = {argv[2]};
    options.bands = {{std::stod(band.substr(0, colon)), std::stod(band.substr(colon + 1))}};
    const jointlab::data::Record record = jointlab::data::read_record(argv[1]);
    jointlab::signal::FftCache cache;
    const jointlab::modal::RecordResult result =
        jointlab::modal::process_record(record, options, cache);
    const jointlab::modal::Backbone& b = result.results.front().ringdown.backbone;
    std::printf("time_s,amplitude,frequency_hz,damping_ratio\n");
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      std::printf("%.6g,%.6g,%.8g,%.6g\n", b.time_s(i), b.amplitude(i), b.frequency_hz(i),
                  b.damping(i));
    }
    std::fprintf(stderr, "backbone: %ld points\n", static_cast<long>(b.size()));
    return b.size() > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "backbone: %s\n", e.what());
    return 2;
  }
}

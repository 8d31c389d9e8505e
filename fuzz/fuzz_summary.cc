// libFuzzer target: the measured side of the updating commands on arbitrary bytes, read twice:
// as summary.json of `jointlab process` (strict JSON, then the fields) and as an update-linear
// modes table (mode,frequency_hz and shape cells, real or complex, ',' ';' or tab delimited)
// against three sensors s1, s2 and s3; and as a sensors file (channel,dof[,sign]).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/measured_data.h"
#include "jointlab/data/modes_table.h"
#include "jointlab/data/process_folder.h"
#include "jointlab/data/sensors_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto& dir = jointlab::fuzz::scratch();
  jointlab::fuzz::write_bytes(dir / "summary.json", data, size);
  try {
    jointlab::data::read_process_run(dir);
  } catch (const jointlab::InputError&) {
  }
  static const std::vector<jointlab::correlate::Sensor> sensors = {
      {"s1", 0, 1.0}, {"s2", 1, -1.0}, {"s3", 2, 1.0}};
  jointlab::fuzz::write_bytes(dir / "modes.csv", data, size);
  try {
    jointlab::correlate::measured_modes(
        jointlab::data::read_modes_table(dir / "modes.csv",
                                         jointlab::correlate::channels_of(sensors)),
        sensors);
  } catch (const jointlab::InputError&) {
  }
  try {
    jointlab::data::parse_sensors_file(std::string(reinterpret_cast<const char*>(data), size),
                                       "sensors.csv");
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

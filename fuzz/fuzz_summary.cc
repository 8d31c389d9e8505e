// libFuzzer target: summary.json of `jointlab process` as the updating commands read it
// (strict JSON, then the fields), on arbitrary bytes.
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "jointlab/core/error.h"
#include "jointlab/correlate/measured_data.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto& dir = jointlab::fuzz::scratch();
  jointlab::fuzz::write_bytes(dir / "summary.json", data, size);
  try {
    jointlab::correlate::read_process_run(dir);
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

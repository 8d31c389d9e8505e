// libFuzzer target: the Matrix Market reader on arbitrary bytes (sizes it declares must be
// refused before they are allocated: -malloc_limit_mb makes a large allocation a finding).
#include <cstddef>
#include <cstdint>

#include "fuzz_util.h"
#include "jointlab/core/error.h"
#include "jointlab/data/matrix_market.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = jointlab::fuzz::scratch() / "fuzz.mtx";
  jointlab::fuzz::write_bytes(path, data, size);
  try {
    jointlab::data::read_matrix_market(path, 4096);
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

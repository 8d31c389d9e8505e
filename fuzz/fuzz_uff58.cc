// libFuzzer target: the UFF dataset 58 / 58b reader on arbitrary bytes.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "jointlab/core/error.h"
#include "jointlab/data/uff58.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const auto rec = jointlab::data::parse_uff58(
        std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.uff");
    // What was read must also write: the writer sees the same hostile names and values.
    (void)jointlab::data::format_uff58(rec, size % 2 == 0);
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

// libFuzzer target: the contract's CSV reader on arbitrary bytes.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "jointlab/core/error.h"
#include "jointlab/data/csv_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    jointlab::data::parse_csv(std::string_view(reinterpret_cast<const char*>(data), size),
                              "fuzz.csv");
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

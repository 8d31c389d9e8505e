// libFuzzer target: the Abaqus matrix reader on arbitrary bytes.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "jointlab/core/error.h"
#include "jointlab/data/abaqus_matrix.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    jointlab::data::parse_abaqus_matrix(std::string_view(reinterpret_cast<const char*>(data), size),
                                        "fuzz.mtx");
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

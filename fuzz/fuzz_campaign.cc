// libFuzzer target: the campaign file reader on arbitrary TOML text.
#include <cstddef>
#include <cstdint>
#include <string>

#include "jointlab/core/error.h"
#include "jointlab/correlate/campaign.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    jointlab::correlate::parse_campaign(std::string(reinterpret_cast<const char*>(data), size),
                                        "/nonexistent/campaign.toml");
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

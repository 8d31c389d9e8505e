// libFuzzer target: the campaign file reader on arbitrary TOML text.
#include <cstddef>
#include <cstdint>
#include <string>

#include "jointlab/campaign/campaign.h"
#include "jointlab/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    jointlab::campaign::parse_campaign(std::string(reinterpret_cast<const char*>(data), size),
                                       "/nonexistent/campaign.toml");
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

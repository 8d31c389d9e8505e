// libFuzzer target: the MATLAB .mat reader (matio underneath) on arbitrary bytes.
//
// matio reads from a path, so each input goes to an in-memory file (memfd) opened by name.
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "jointlab/core/error.h"
#include "jointlab/data/mat_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const int fd = memfd_create("jointlab-fuzz-mat", 0);
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  if (fd < 0) std::abort();
  if (ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != static_cast<ssize_t>(size)) {
    std::abort();
  }
  try {
    jointlab::data::read_mat(path);
  } catch (const jointlab::InputError&) {
  }
  return 0;
}

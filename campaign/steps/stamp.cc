#include "jointlab/campaign/steps/stamp.h"

#include <cstdint>
#include <fstream>
#include <iterator>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/atomic_file.h"

#ifndef JOINTLAB_VERSION
#error "JOINTLAB_VERSION must be defined by the build"
#endif

namespace jointlab::campaign {

namespace fs = std::filesystem;

namespace {

// FNV-1a, 64 bit: a few lines for a cache key; no hashing library is among the dependencies.
struct Fnv {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  void add(const char* p, size_t n) {
    for (size_t i = 0; i < n; ++i) {
      h ^= static_cast<unsigned char>(p[i]);
      h *= 0x100000001b3ULL;
    }
  }
  void add(const std::string& s) {
    add(s.data(), s.size());
    add("\0", 1);  // separates consecutive parts
  }
};

}  // namespace

std::string program_version() { return std::string("jointlab ") + JOINTLAB_VERSION; }

std::string input_stamp(const std::vector<fs::path>& files, const std::string& settings) {
  Fnv f;
  f.add(program_version());
  f.add(settings);
  for (const fs::path& p : files) {
    std::ifstream in(p, std::ios::binary);
    if (!in) throw InputError(fmt::format("{}: cannot read", p.string()));
    char buf[1 << 16];
    while (in.read(buf, sizeof buf) || in.gcount() > 0)
      f.add(buf, static_cast<size_t>(in.gcount()));
    f.add("\0", 1);
  }
  return fmt::format("{:016x}", f.h);
}

bool stamp_matches(const fs::path& stamp_file, const std::string& stamp) {
  std::ifstream in(stamp_file);
  if (!in) return false;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return text == stamp + "\n";
}

void write_stamp(const fs::path& stamp_file, const std::string& stamp) {
  data::write_file_atomically(stamp_file, stamp + "\n");
}

}  // namespace jointlab::campaign

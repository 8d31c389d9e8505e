#include "jointlab/campaign/steps/stamp.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include <link.h>

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

// The loaded object (the executable, or the Python module's library) that holds `address`,
// and from it the GNU build ID its linker wrote (a digest of the linked code and data) or,
// where it has none, a digest of its read-only segments (its code and constants, the same
// bytes at any load address). dl_iterate_phdr's callback: 1 once the object is met.
struct CodeDigest {
  std::uintptr_t address = 0;
  std::string digest;
};

int digest_of_object(dl_phdr_info* info, size_t, void* data) {
  auto& d = *static_cast<CodeDigest*>(data);
  bool holds = false;
  for (ElfW(Half) i = 0; i < info->dlpi_phnum && !holds; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    const std::uintptr_t start = info->dlpi_addr + ph.p_vaddr;
    holds = ph.p_type == PT_LOAD && d.address >= start && d.address < start + ph.p_memsz;
  }
  if (!holds) return 0;
  for (ElfW(Half) i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    if (ph.p_type != PT_NOTE) continue;
    const char* p = reinterpret_cast<const char*>(info->dlpi_addr + ph.p_vaddr);
    const char* const end = p + ph.p_memsz;
    const auto align4 = [](ElfW(Word) n) { return (n + 3) & ~ElfW(Word){3}; };
    while (p + sizeof(ElfW(Nhdr)) <= end) {
      ElfW(Nhdr) note;
      std::memcpy(&note, p, sizeof note);
      const char* name = p + sizeof note;
      const char* desc = name + align4(note.n_namesz);
      if (desc + note.n_descsz > end) break;
      if (note.n_type == NT_GNU_BUILD_ID && note.n_namesz == 4 &&
          std::memcmp(name, "GNU", 4) == 0) {
        for (ElfW(Word) k = 0; k < note.n_descsz; ++k)
          d.digest += fmt::format("{:02x}", static_cast<unsigned char>(desc[k]));
        return 1;
      }
      p = desc + align4(note.n_descsz);
    }
  }
  Fnv f;
  for (ElfW(Half) i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    if (ph.p_type == PT_LOAD && !(ph.p_flags & PF_W))
      f.add(reinterpret_cast<const char*>(info->dlpi_addr + ph.p_vaddr), ph.p_filesz);
  }
  d.digest = fmt::format("{:016x}", f.h);
  return 1;
}

}  // namespace

std::string program_version() { return std::string("jointlab ") + JOINTLAB_VERSION; }

std::string build_identity() {
  static const std::string identity = [] {
    CodeDigest d;
    d.address = reinterpret_cast<std::uintptr_t>(&digest_of_object);
    dl_iterate_phdr(&digest_of_object, &d);
    // Code that cannot be found is taken as this process's own: its stamps match no other's.
    if (d.digest.empty()) d.digest = fmt::format("unknown {:016x}", std::random_device{}());
    return program_version() + " code " + d.digest;
  }();
  return identity;
}

std::string input_stamp(const std::vector<fs::path>& files, const std::string& settings) {
  Fnv f;
  f.add(build_identity());
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

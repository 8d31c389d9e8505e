#include "jointlab/campaign/steps/stamp.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <string_view>

#include <link.h>

#include <fmt/format.h>

#include "jointlab/campaign/steps/stamp_detail.h"
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

// The code_digest of the loaded object (the executable, or the Python module's library) that
// holds `address`, then those of jointlab's own shared libraries (libjointlab_*.so, loaded only
// in a -DBUILD_SHARED_LIBS=ON build, where the process step's code is not in the object that
// holds this function). dl_iterate_phdr's callback, over every loaded object.
struct CodeDigest {
  std::uintptr_t address = 0;
  std::string digest;
  std::string libraries;
};

int digest_of_object(dl_phdr_info* info, size_t, void* data) {
  auto& d = *static_cast<CodeDigest*>(data);
  bool holds = false;
  for (ElfW(Half) i = 0; i < info->dlpi_phnum && !holds; ++i) {
    const ElfW(Phdr)& ph = info->dlpi_phdr[i];
    const std::uintptr_t start = info->dlpi_addr + ph.p_vaddr;
    holds = ph.p_type == PT_LOAD && d.address >= start && d.address < start + ph.p_memsz;
  }
  const std::string_view name = info->dlpi_name ? info->dlpi_name : "";
  const bool ours = name.find("libjointlab_") != std::string_view::npos;
  if (!holds && !ours) return 0;
  const std::string digest =
      detail::code_digest(info->dlpi_addr, info->dlpi_phdr, info->dlpi_phnum);
  if (holds) d.digest = digest;
  if (ours && !holds) d.libraries += " " + digest;
  return 0;
}

// The GNU build ID in one PT_NOTE segment of `size` bytes at `p`, aligned to `align`; "" none.
// Offsets, not pointers, are compared with the size, so that no length read can run past it.
std::string build_id_note(const char* p, std::size_t size, std::size_t align) {
  const auto pad = [align](std::size_t n) { return (n + align - 1) & ~(align - 1); };
  std::size_t off = 0;
  while (off <= size && size - off >= sizeof(ElfW(Nhdr))) {
    ElfW(Nhdr) note;
    std::memcpy(&note, p + off, sizeof note);
    const std::size_t name = off + sizeof note;
    if (note.n_namesz > size - name) break;
    const std::size_t desc = pad(name + note.n_namesz);
    if (desc > size || note.n_descsz > size - desc) break;
    if (note.n_type == NT_GNU_BUILD_ID && note.n_namesz == 4 && note.n_descsz > 0 &&
        std::memcmp(p + name, "GNU", 4) == 0) {
      std::string id;
      for (std::size_t k = 0; k < note.n_descsz; ++k)
        id += fmt::format("{:02x}", static_cast<unsigned char>(p[desc + k]));
      return id;
    }
    off = pad(desc + note.n_descsz);
  }
  return "";
}

}  // namespace

std::string detail::code_digest(std::uintptr_t base, const ElfW(Phdr) * phdr, std::size_t count) {
  // A PT_NOTE outside every PT_LOAD is not in memory: objcopy --remove-section
  // .note.gnu.build-id leaves one at address 0, which a non-PIE or static program would read
  // at address 0 (before, a segmentation fault in build_identity()).
  const auto loaded = [&](ElfW(Addr) at, std::size_t size) {
    for (std::size_t i = 0; i < count; ++i) {
      const ElfW(Phdr)& ph = phdr[i];
      if (ph.p_type == PT_LOAD && at >= ph.p_vaddr && size <= ph.p_filesz &&
          at - ph.p_vaddr <= ph.p_filesz - size)
        return true;
    }
    return false;
  };
  for (std::size_t i = 0; i < count; ++i) {
    const ElfW(Phdr)& ph = phdr[i];
    if (ph.p_type != PT_NOTE || !loaded(ph.p_vaddr, ph.p_memsz)) continue;
    const std::string id = build_id_note(reinterpret_cast<const char*>(base + ph.p_vaddr),
                                         ph.p_memsz, ph.p_align == 8 ? 8 : 4);
    if (!id.empty()) return id;
  }
  Fnv f;
  for (std::size_t i = 0; i < count; ++i) {
    const ElfW(Phdr)& ph = phdr[i];
    if (ph.p_type == PT_LOAD && !(ph.p_flags & PF_W))
      f.add(reinterpret_cast<const char*>(base + ph.p_vaddr), ph.p_filesz);
  }
  return fmt::format("{:016x}", f.h);
}

std::string program_version() { return std::string("jointlab ") + JOINTLAB_VERSION; }

std::string build_identity() {
  static const std::string identity = [] {
    CodeDigest d;
    d.address = reinterpret_cast<std::uintptr_t>(&digest_of_object);
    dl_iterate_phdr(&digest_of_object, &d);
    // Code that cannot be found is taken as this process's own: its stamps match no other's.
    if (d.digest.empty()) d.digest = fmt::format("unknown {:016x}", std::random_device{}());
    return program_version() + " code " + d.digest + d.libraries;
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

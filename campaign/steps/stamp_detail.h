// build_identity()'s reading of one loaded object (campaign/steps/stamp.h), apart so that its
// test can give it made-up program headers. Hand-written on dl_iterate_phdr's view (glibc's
// <link.h>): the build ID is wanted from the code running, in memory, and glibc has no call
// that returns it; ELF libraries (libelf, LIEF) read files, which a rebuild may have replaced.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <link.h>

namespace jointlab::campaign::detail {

/// The GNU build ID (hex) of the object loaded at `base` with program headers `phdr` (`count`
/// of them), read only from PT_NOTE segments inside one of its PT_LOAD segments, notes padded
/// to the segment's alignment (4, or 8); where it has none, the 64-bit FNV-1a digest (16 hex
/// digits) of its read-only PT_LOAD segments.
std::string code_digest(std::uintptr_t base, const ElfW(Phdr) * phdr, std::size_t count);

}  // namespace jointlab::campaign::detail

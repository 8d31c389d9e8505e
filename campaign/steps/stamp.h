// Whether a cached result of a campaign run (the model built from a description, a processed
// hit) is still valid: a stamp file beside it holds a digest of everything the result depends
// on, the content of its input files, every setting that enters it and the program's build
// (its version and the linker's build ID of its code: build_identity); the result is reused
// only when the digest of the present inputs is the same. Unlike file times this also catches
// changed settings, a folder holding another campaign's results and results an earlier build
// of the same version computed (the version alone let a run on 2026-11-29 reuse hits processed
// before e260cd2 changed their first points' damping_std, up to 1.30x, and report them as its
// own).
// Digest: 64-bit FNV-1a, a cache key rather than a security measure (collisions need
// deliberate effort), written in hexadecimal.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace jointlab::campaign {

/// The program's version ("jointlab 0.1.0").
std::string program_version();

/// The program's version and the build ID of the executable or library running it
/// ("jointlab 0.1.0 code 3741ed3d..."), which stamps take in.
std::string build_identity();

/// The digest of build_identity(), the files' contents (in order) and the settings text;
/// InputError naming a file that cannot be read.
std::string input_stamp(const std::vector<std::filesystem::path>& files,
                        const std::string& settings);

/// True when `stamp_file` exists and holds exactly `stamp`.
bool stamp_matches(const std::filesystem::path& stamp_file, const std::string& stamp);

/// Writes `stamp` to `stamp_file` (atomically).
void write_stamp(const std::filesystem::path& stamp_file, const std::string& stamp);

}  // namespace jointlab::campaign

// Channel names read from test files: their limit and their form in output file names.
//
// Outputs are named after channels (`<file stem>.<channel>.band<k>.csv`), so every reader
// refuses a channel name longer than kMaxChannelNameBytes, and two channels whose names
// give the same file name part. In a file name, each byte that is not part of valid UTF-8,
// '/', and each control character (NUL included) becomes '_': the name on disk is then valid
// UTF-8 and the same, byte for byte, as the one summary.json gives.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace jointlab::data {

/// The longest channel name a reader accepts, in bytes.
inline constexpr size_t kMaxChannelNameBytes = 128;

/// The longest output file name, in bytes: 255 (NAME_MAX of common file systems) less the
/// 13 bytes of ".tmp-XXXXXXXX" that its temporary adds while it is written (atomic_file.h).
inline constexpr size_t kMaxFileNameBytes = 242;

/// Length of the well-formed UTF-8 sequence starting at s[i] (RFC 3629: no overlong forms,
/// no surrogates, nothing above U+10FFFF), or 0 if the bytes there are not one.
size_t utf8_sequence_length(std::string_view s, size_t i);

/// `name` as a part of a file name: bytes outside valid UTF-8, '/', and control characters
/// (below 0x20, and 0x7F) replaced by '_'.
std::string file_name_part(std::string_view name);

/// Throws InputError naming `file` (and `line` when > 0) if a channel name is longer than
/// kMaxChannelNameBytes or two names have the same file_name_part.
void check_channel_names(const std::vector<std::string>& names, const std::string& file,
                         long line = 0);

/// Throws InputError naming both files if two of `files` have stems with the same
/// file_name_part: outputs named after their stems (`process`, `stepped-sine`) would collide.
void check_distinct_stems(const std::vector<std::string>& files);

}  // namespace jointlab::data

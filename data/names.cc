#include "jointlab/data/names.h"

#include <filesystem>
#include <map>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/core/text.h"

namespace jointlab::data {

size_t utf8_sequence_length(std::string_view s, size_t i) {
  const auto b = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  size_t n = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (i + n > s.size() || b(i + 1) < lo || b(i + 1) > hi) return 0;
  for (size_t k = 2; k < n; ++k) {
    if (b(i + k) < 0x80 || b(i + k) > 0xBF) return 0;
  }
  return n;
}

std::string file_name_part(std::string_view name) {
  std::string out;
  out.reserve(name.size());
  for (size_t i = 0; i < name.size();) {
    const auto u = static_cast<unsigned char>(name[i]);
    if (u >= 0x80) {
      const size_t n = utf8_sequence_length(name, i);
      out.append(n > 0 ? name.substr(i, n) : "_");
      i += n > 0 ? n : 1;
      continue;
    }
    out.push_back(u < 0x20 || u == 0x7F || u == '/' ? '_' : name[i]);
    ++i;
  }
  return out;
}

void check_channel_names(const std::vector<std::string>& names, const std::string& file,
                         long line) {
  std::map<std::string, const std::string*> parts;
  for (const std::string& name : names) {
    if (name.size() > kMaxChannelNameBytes) {
      throw InputError(where(file, line,
                             fmt::format("channel name of {} bytes ('{}...'): at most {} (names "
                                         "make output file names)",
                                         name.size(), printable(name), kMaxChannelNameBytes)));
    }
    const auto [it, fresh] = parts.emplace(file_name_part(name), &name);
    if (!fresh) {
      throw InputError(where(
          file, line,
          fmt::format("channels '{}' and '{}' both make output file names with '{}' (bytes "
                      "that are not UTF-8, '/' and control characters become '_'); rename one",
                      printable(*it->second), printable(name), it->first)));
    }
  }
}

void check_distinct_stems(const std::vector<std::string>& files) {
  namespace fs = std::filesystem;
  for (size_t i = 0; i < files.size(); ++i) {
    for (size_t k = 0; k < i; ++k) {
      if (file_name_part(fs::path(files[i]).stem().string()) ==
          file_name_part(fs::path(files[k]).stem().string())) {
        throw InputError(fmt::format("{} and {} share the name '{}': outputs would collide",
                                     files[k], files[i], fs::path(files[i]).stem().string()));
      }
    }
  }
}

}  // namespace jointlab::data

#include "jointlab/apps/cli_args.h"

#include <filesystem>

#include <fmt/format.h>

#include "jointlab/core/error.h"
#include "jointlab/data/names.h"

namespace jointlab::apps {

Quantity motion_quantity(const std::string& option, const std::string& value) {
  const auto q = parse_quantity(value);
  if (!q || *q == Quantity::kForce) {
    throw InputError(
        fmt::format("{} {}: expected displacement, velocity or acceleration", option, value));
  }
  return *q;
}

void check_distinct_stems(const std::vector<std::string>& files) {
  namespace fs = std::filesystem;
  for (size_t i = 0; i < files.size(); ++i) {
    for (size_t k = 0; k < i; ++k) {
      // Output names carry the stem as data::file_name_part gives it.
      if (data::file_name_part(fs::path(files[i]).stem().string()) ==
          data::file_name_part(fs::path(files[k]).stem().string())) {
        throw InputError(fmt::format("{} and {} share the name '{}': outputs would collide",
                                     files[k], files[i], fs::path(files[i]).stem().string()));
      }
    }
  }
}

}  // namespace jointlab::apps

#include "jointlab/data/table_writer.h"

#include <cassert>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "jointlab/data/atomic_file.h"

namespace jointlab::data {

void Table::add(std::string name, Eigen::VectorXd values) {
  assert(columns.empty() || values.size() == columns.front().size());
  names.push_back(std::move(name));
  columns.push_back(std::move(values));
  exact.push_back(0);
  optional.push_back(0);
}

void Table::add_exact(std::string name, Eigen::VectorXd values) {
  add(std::move(name), std::move(values));
  exact.back() = 1;
}

void Table::add_optional(std::string name, Eigen::VectorXd values) {
  add(std::move(name), std::move(values));
  optional.back() = 1;
}

void Table::add(std::initializer_list<std::pair<std::string, Eigen::VectorXd>> named_columns) {
  for (const auto& [name, values] : named_columns) add(name, values);
}

void write_table(const std::filesystem::path& path, const Table& table) {
  std::string text;
  for (size_t c = 0; c < table.names.size(); ++c) {
    if (c) text += ',';
    text += table.names[c];
  }
  text += '\n';
  for (Eigen::Index r = 0; r < table.rows(); ++r) {
    for (size_t c = 0; c < table.columns.size(); ++c) {
      const double v = table.columns[c](r);
      const bool is_exact = c < table.exact.size() && table.exact[c];
      const bool is_optional = c < table.optional.size() && table.optional[c];
      if (is_optional && std::isnan(v)) {
        if (c) text += ',';
        continue;
      }
      if (!std::isfinite(v)) {
        throw std::logic_error(
            fmt::format("{}: refusing to write a non-finite value in column "
                        "'{}', row {}",
                        path.string(), table.names[c], r + 1));
      }
      if (c) text += ',';
      text += is_exact ? fmt::format("{}", v) : fmt::format("{:.10g}", v);
    }
    text += '\n';
  }
  write_file_atomically(path, text);
}

}  // namespace jointlab::data

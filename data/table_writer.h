// CSV result tables: named numeric columns, written atomically.
//
// Values are printed with 10 significant digits ("%.10g"), enough for every
// result jointlab reports; a column added with add_exact() is printed in full (the shortest
// text that reads back to the same double: a time of 1.7e9 s, Unix time, keeps its
// microseconds). A NaN or Inf in a result is a bug upstream; the writer refuses it
// (std::logic_error) rather than print it, except in a column added with add_optional(),
// where NaN means "absent" and is written as an empty cell (never 0 standing in for "none").
#pragma once

#include <filesystem>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace jointlab::data {

/// A result table: column names and equally long columns.
struct Table {
  std::vector<std::string> names;        ///< header row
  std::vector<Eigen::VectorXd> columns;  ///< one vector per name
  std::vector<char> exact;               ///< per column: printed in full
  std::vector<char> optional;            ///< per column: NaN is an absent (empty) cell

  /// Appends a column; asserts equal length with the first.
  void add(std::string name, Eigen::VectorXd values);
  /// Appends a column printed in full precision (shortest round-trip text).
  void add_exact(std::string name, Eigen::VectorXd values);
  /// Appends a column whose NaN entries are absent values, written as empty cells.
  void add_optional(std::string name, Eigen::VectorXd values);
  /// Appends the columns in the order given (each as add()).
  void add(std::initializer_list<std::pair<std::string, Eigen::VectorXd>> named_columns);
  /// Number of rows (0 if no column).
  Eigen::Index rows() const { return columns.empty() ? 0 : columns.front().size(); }
};

/// Writes `table` as comma-separated text to `path` (temporary name, then rename).
void write_table(const std::filesystem::path& path, const Table& table);

}  // namespace jointlab::data

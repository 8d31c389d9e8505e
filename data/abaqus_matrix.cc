#include "jointlab/data/abaqus_matrix.h"

#include "jointlab/core/text.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab::data {
namespace {

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  const bool commas = line.find(',') != std::string_view::npos;
  size_t pos = 0;
  while (pos <= line.size()) {
    if (commas) {
      const size_t end = line.find(',', pos);
      const size_t stop = end == std::string_view::npos ? line.size() : end;
      out.push_back(trim(line.substr(pos, stop - pos)));
      pos = stop + 1;
    } else {
      const size_t start = line.find_first_not_of(" \t", pos);
      if (start == std::string_view::npos) break;
      const size_t end = line.find_first_of(" \t", start);
      const size_t stop = end == std::string_view::npos ? line.size() : end;
      out.push_back(line.substr(start, stop - start));
      pos = stop;
    }
  }
  if (commas && !out.empty() && out.back().empty()) out.pop_back();  // trailing comma
  return out;
}

template <typename T>
std::optional<T> parse_number(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  T v{};
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

struct Entry {
  DofLabel row, col;
  double value;
  long line;
};

Eigen::SparseMatrix<double> assemble(const std::vector<Entry>& entries,
                                     const std::vector<DofLabel>& dofs, const std::string& file) {
  auto index = [&](const DofLabel& d) {
    return static_cast<int>(std::lower_bound(dofs.begin(), dofs.end(), d) - dofs.begin());
  };
  // Which triangles are stored decides whether entries are mirrored.
  bool lower = false, upper = false;
  for (const Entry& e : entries) {
    if (e.row < e.col) upper = true;
    if (e.col < e.row) lower = true;
  }
  const bool full = lower && upper;
  std::map<std::pair<int, int>, std::pair<double, long>> seen;
  for (const Entry& e : entries) {
    const auto key = std::make_pair(index(e.row), index(e.col));
    const auto [it, inserted] = seen.emplace(key, std::make_pair(e.value, e.line));
    if (!inserted) {
      throw InputError(where(file, e.line,
                             fmt::format("entry ({}:{}, {}:{}) given twice (first "
                                         "at line {})",
                                         e.row.node, e.row.component, e.col.node, e.col.component,
                                         it->second.second)));
    }
  }
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(entries.size() * 2);
  for (const auto& [key, v] : seen) {
    const auto [i, j] = key;
    if (full && i != j) {
      const auto mirror = seen.find({j, i});
      const double a = v.first;
      const double b = mirror == seen.end() ? 0.0 : mirror->second.first;
      if (std::abs(a - b) > 1e-9 * std::max(std::abs(a), std::abs(b))) {
        throw InputError(where(file, v.second,
                               fmt::format("matrix stored in full is not "
                                           "symmetric: entry {} here, {} at the "
                                           "mirrored position",
                                           a, b)));
      }
      triplets.emplace_back(i, j, a);
    } else {
      triplets.emplace_back(i, j, v.first);
      if (i != j) triplets.emplace_back(j, i, v.first);
    }
  }
  const auto n = static_cast<Eigen::Index>(dofs.size());
  Eigen::SparseMatrix<double> m(n, n);
  m.setFromTriplets(triplets.begin(), triplets.end());
  return m;
}

std::string load(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where(path.string(), 0, "cannot open file"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(where(path.string(), 0, "read error"));
  return text;
}

}  // namespace

AbaqusMatrix parse_abaqus_matrix(std::string_view text, const std::string& name) {
  std::vector<Entry> entries;
  size_t layout = 0;  // 5 (MATRIX INPUT) or 3 (COORDINATE), fixed by the first entry
  size_t pos = 0;
  long line_no = 0;
  while (pos < text.size()) {
    const size_t end = text.find('\n', pos);
    const size_t stop = end == std::string_view::npos ? text.size() : end;
    const std::string_view line = trim(text.substr(pos, stop - pos));
    pos = stop + 1;
    ++line_no;
    if (line.empty() || line.front() == '*') continue;
    const auto fields = split(line);
    if (fields.size() != 3 && fields.size() != 5) {
      throw InputError(where(name, line_no,
                             fmt::format("{} fields; expected 'node, DOF, node, "
                                         "DOF, value' or 'row, column, value'",
                                         fields.size())));
    }
    if (layout == 0) layout = fields.size();
    if (fields.size() != layout) {
      throw InputError(where(name, line_no,
                             fmt::format("{} fields after lines of {}: one layout "
                                         "per file",
                                         fields.size(), layout)));
    }
    Entry e{};
    e.line = line_no;
    const auto value = parse_number<double>(fields.back());
    if (!value) {
      throw InputError(where(name, line_no,
                             fmt::format("value '{}' is not a number", printable(fields.back()))));
    }
    if (!std::isfinite(*value)) {
      throw InputError(
          where(name, line_no, fmt::format("value {} (NaN and Inf are not allowed)", *value)));
    }
    e.value = *value;
    std::optional<long> ints[4];
    const size_t n_int = layout - 1;
    for (size_t i = 0; i < n_int; ++i) {
      ints[i] = parse_number<long>(fields[i]);
      if (!ints[i]) {
        throw InputError(
            where(name, line_no,
                  fmt::format("field {} '{}' is not an integer", i + 1, printable(fields[i]))));
      }
    }
    if (layout == 5) {
      for (size_t i : {1u, 3u}) {
        if (*ints[i] < 1 || *ints[i] > 99) {
          throw InputError(where(name, line_no,
                                 fmt::format("field {}: DOF {} is not between 1 "
                                             "and 99",
                                             i + 1, *ints[i])));
        }
      }
      e.row = DofLabel{*ints[0], static_cast<int>(*ints[1])};
      e.col = DofLabel{*ints[2], static_cast<int>(*ints[3])};
    } else {
      for (size_t i : {0u, 1u}) {
        if (*ints[i] < 1) {
          throw InputError(where(name, line_no,
                                 fmt::format("field {}: equation number {} is not "
                                             "positive (1-based)",
                                             i + 1, *ints[i])));
        }
      }
      e.row = DofLabel{*ints[0], 0};
      e.col = DofLabel{*ints[1], 0};
    }
    entries.push_back(e);
  }
  if (entries.empty()) throw InputError(where(name, line_no, "no matrix entries"));
  AbaqusMatrix out;
  for (const Entry& e : entries) {
    out.dofs.push_back(e.row);
    out.dofs.push_back(e.col);
  }
  std::sort(out.dofs.begin(), out.dofs.end());
  out.dofs.erase(std::unique(out.dofs.begin(), out.dofs.end()), out.dofs.end());
  if (out.dofs.size() > static_cast<size_t>(std::numeric_limits<int>::max())) {
    throw InputError(where(name, 0, "too many degrees of freedom"));
  }
  out.matrix = assemble(entries, out.dofs, name);
  return out;
}

AbaqusMatrix read_abaqus_matrix(const std::filesystem::path& path) {
  return parse_abaqus_matrix(load(path), path.string());
}

AbaqusModel read_abaqus_model(const std::filesystem::path& mass,
                              const std::filesystem::path& stiffness) {
  AbaqusMatrix m = read_abaqus_matrix(mass);
  AbaqusMatrix k = read_abaqus_matrix(stiffness);
  const bool m_coord = !m.dofs.empty() && m.dofs.front().component == 0;
  const bool k_coord = !k.dofs.empty() && k.dofs.front().component == 0;
  if (m_coord != k_coord) {
    throw InputError(where(stiffness.string(), 0,
                           fmt::format("one file uses node/DOF labels and "
                                       "the other equation numbers ({})",
                                       mass.string())));
  }
  AbaqusModel out;
  out.dofs = m.dofs;
  out.dofs.insert(out.dofs.end(), k.dofs.begin(), k.dofs.end());
  std::sort(out.dofs.begin(), out.dofs.end());
  out.dofs.erase(std::unique(out.dofs.begin(), out.dofs.end()), out.dofs.end());
  auto expand = [&](const AbaqusMatrix& a) {
    std::vector<Eigen::Triplet<double>> t;
    std::vector<int> map(a.dofs.size());
    for (size_t i = 0; i < a.dofs.size(); ++i) {
      map[i] = static_cast<int>(std::lower_bound(out.dofs.begin(), out.dofs.end(), a.dofs[i]) -
                                out.dofs.begin());
    }
    for (int c = 0; c < a.matrix.outerSize(); ++c) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(a.matrix, c); it; ++it) {
        t.emplace_back(map[static_cast<size_t>(it.row())], map[static_cast<size_t>(it.col())],
                       it.value());
      }
    }
    const auto n = static_cast<Eigen::Index>(out.dofs.size());
    Eigen::SparseMatrix<double> s(n, n);
    s.setFromTriplets(t.begin(), t.end());
    return s;
  };
  out.mass = expand(m);
  out.stiffness = expand(k);
  return out;
}

}  // namespace jointlab::data

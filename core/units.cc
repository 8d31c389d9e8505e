#include "jointlab/core/units.h"

#include "jointlab/core/text.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cctype>

#include <fmt/format.h>

#include "jointlab/core/error.h"

namespace jointlab {

std::string where(const std::string& file, long line, const std::string& message) {
  if (line > 0) return fmt::format("{}:{}: {}", file, line, message);
  return fmt::format("{}: {}", file, message);
}

namespace {

constexpr double kStandardGravity = 9.80665;     // m/s^2, by definition (CGPM 1901)
constexpr double kInch = 0.0254;                 // m, exact
constexpr double kPoundForce = 4.4482216152605;  // N, exact from lb and g

struct Entry {
  std::string_view name;
  Quantity quantity;
  double to_si;
};

// Spellings seen in data-acquisition exports; compared after removing spaces.
constexpr std::array kUnits = {
    Entry{"m", Quantity::kDisplacement, 1.0},
    Entry{"mm", Quantity::kDisplacement, 1e-3},
    Entry{"um", Quantity::kDisplacement, 1e-6},
    Entry{"µm", Quantity::kDisplacement, 1e-6},
    Entry{"micron", Quantity::kDisplacement, 1e-6},
    Entry{"in", Quantity::kDisplacement, kInch},
    Entry{"m/s", Quantity::kVelocity, 1.0},
    Entry{"mm/s", Quantity::kVelocity, 1e-3},
    Entry{"um/s", Quantity::kVelocity, 1e-6},
    Entry{"µm/s", Quantity::kVelocity, 1e-6},
    Entry{"in/s", Quantity::kVelocity, kInch},
    Entry{"m/s^2", Quantity::kAcceleration, 1.0},
    Entry{"m/s2", Quantity::kAcceleration, 1.0},
    Entry{"m/s²", Quantity::kAcceleration, 1.0},
    Entry{"mm/s^2", Quantity::kAcceleration, 1e-3},
    Entry{"mm/s2", Quantity::kAcceleration, 1e-3},
    Entry{"mm/s²", Quantity::kAcceleration, 1e-3},
    Entry{"in/s^2", Quantity::kAcceleration, kInch},
    Entry{"in/s2", Quantity::kAcceleration, kInch},
    Entry{"g", Quantity::kAcceleration, kStandardGravity},
    Entry{"mg", Quantity::kAcceleration, 1e-3 * kStandardGravity},
    Entry{"N", Quantity::kForce, 1.0},
    Entry{"kN", Quantity::kForce, 1e3},
    Entry{"lbf", Quantity::kForce, kPoundForce},
};

std::string normalise(std::string_view text) {
  std::string s;
  for (char c : text) {
    if (!std::isspace(static_cast<unsigned char>(c))) s.push_back(c);
  }
  return s;
}

}  // namespace

std::optional<Unit> parse_unit(std::string_view text) {
  const std::string s = normalise(text);
  // Case matters for m (metre) vs M and g vs G; only force units are case-blind.
  for (const Entry& e : kUnits) {
    const bool match = e.quantity == Quantity::kForce ? lower(s) == lower(e.name) : s == e.name;
    if (match) return Unit{e.quantity, e.to_si, s};
  }
  return std::nullopt;
}

std::vector<std::string> unit_spellings(Quantity q) {
  std::vector<std::string> out;
  for (const Entry& e : kUnits) {
    if (e.quantity == q) out.emplace_back(e.name);
  }
  return out;
}

std::vector<std::string> unit_names(Quantity q) {
  std::vector<std::string> out;
  std::vector<double> factors;
  for (const Entry& e : kUnits) {
    if (e.quantity != q || std::find(factors.begin(), factors.end(), e.to_si) != factors.end())
      continue;
    factors.push_back(e.to_si);
    out.emplace_back(e.name);
  }
  return out;
}

std::string known_units() {
  std::string out;
  for (const Quantity q :
       {Quantity::kDisplacement, Quantity::kVelocity, Quantity::kAcceleration, Quantity::kForce}) {
    for (const std::string& name : unit_names(q)) out += (out.empty() ? "" : ", ") + name;
  }
  return out;
}

std::string si_unit(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement:
      return "m";
    case Quantity::kVelocity:
      return "m/s";
    case Quantity::kAcceleration:
      return "m/s^2";
    case Quantity::kForce:
      return "N";
  }
  return "";
}

std::string quantity_name(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement:
      return "displacement";
    case Quantity::kVelocity:
      return "velocity";
    case Quantity::kAcceleration:
      return "acceleration";
    case Quantity::kForce:
      return "force";
  }
  return "";
}

std::optional<Quantity> parse_quantity(std::string_view text) {
  for (Quantity q :
       {Quantity::kDisplacement, Quantity::kVelocity, Quantity::kAcceleration, Quantity::kForce}) {
    if (text == quantity_name(q)) return q;
  }
  return std::nullopt;
}

Quantity motion_quantity(std::string_view option, std::string_view value) {
  const std::optional<Quantity> q = parse_quantity(value);
  if (!q || *q == Quantity::kForce) {
    throw InputError(fmt::format("{} {}: expected displacement, velocity or acceleration", option,
                                 value.empty() ? "''" : value));
  }
  return *q;
}

int derivative_order(Quantity q) {
  switch (q) {
    case Quantity::kDisplacement:
      return 0;
    case Quantity::kVelocity:
      return 1;
    case Quantity::kAcceleration:
      return 2;
    case Quantity::kForce:
      break;
  }
  assert(false && "force is not a derivative of displacement");
  return -1;
}

}  // namespace jointlab

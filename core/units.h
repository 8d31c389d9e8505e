// Physical quantities and units of test channels.
//
// Every sample inside jointlab is SI: metres, m/s, m/s^2, newtons, seconds.
// A unit string as written in a file header ("g", "mm/s", "m/s^2", "N") maps to
// the quantity it measures and the factor that converts it to SI:
// value_SI = factor * value_in_unit. Standard gravity g = 9.80665 m/s^2.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace jointlab {

/// The physical quantity a channel measures.
enum class Quantity { kDisplacement, kVelocity, kAcceleration, kForce };

/// A parsed unit: what it measures and the factor to SI.
struct Unit {
  Quantity quantity;
  double to_si;       ///< value_SI = to_si * value
  std::string label;  ///< the unit as written, normalised ("m/s^2")
};

/// Looks up a unit string ("g", "m/s^2", "mm/s", "in", "N", ...); nullopt if unknown.
std::optional<Unit> parse_unit(std::string_view text);

/// Every spelling parse_unit reads as a unit of `q`, in the order of its one table: displacement
/// "m", "mm", "um", "µm", "micron", "in". A force's are read case-blind ("N" also as "n").
std::vector<std::string> unit_spellings(Quantity q);

/// One spelling per unit of `q` (the first of those with the same factor to SI), for messages
/// that list what a column takes: displacement "m", "mm", "um", "in".
std::vector<std::string> unit_names(Quantity q);

/// Every unit parse_unit reads, one spelling each, for a refusal of an unknown one:
/// "m, mm, um, in, m/s, mm/s, um/s, in/s, m/s^2, mm/s^2, in/s^2, g, mg, N, kN, lbf".
std::string known_units();

/// The SI unit of a quantity: "m", "m/s", "m/s^2", "N".
std::string si_unit(Quantity q);

/// Lower-case name of a quantity: "displacement", "velocity", "acceleration", "force".
std::string quantity_name(Quantity q);

/// Parses "displacement" | "velocity" | "acceleration" | "force"; nullopt otherwise.
std::optional<Quantity> parse_quantity(std::string_view text);

/// The motion quantity an option's `value` names (displacement, velocity or acceleration);
/// InputError "OPTION VALUE: expected displacement, velocity or acceleration" for anything else,
/// force included.
Quantity motion_quantity(std::string_view option, std::string_view value);

/// Order of time differentiation from displacement: 0, 1, 2 (force: not a motion, asserts).
int derivative_order(Quantity q);

}  // namespace jointlab

#include "jointlab/core/units.h"

#include <string>
#include <string_view>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"

namespace jointlab {
namespace {

TEST(Units, StandardGravityIsExact) {
  const auto g = parse_unit("g");
  ASSERT_TRUE(g.has_value());
  EXPECT_EQ(g->quantity, Quantity::kAcceleration);
  EXPECT_DOUBLE_EQ(g->to_si, 9.80665);
}

TEST(Units, SpellingsOfAccelerationAgree) {
  for (const char* s : {"m/s^2", "m/s2", "m / s^2"}) {
    const auto u = parse_unit(s);
    ASSERT_TRUE(u.has_value()) << s;
    EXPECT_EQ(u->quantity, Quantity::kAcceleration);
    EXPECT_DOUBLE_EQ(u->to_si, 1.0);
  }
}

TEST(Units, ScaledUnits) {
  EXPECT_DOUBLE_EQ(parse_unit("mm")->to_si, 1e-3);
  EXPECT_EQ(parse_unit("mm/s")->quantity, Quantity::kVelocity);
  EXPECT_DOUBLE_EQ(parse_unit("in/s")->to_si, 0.0254);
  EXPECT_EQ(parse_unit("N")->quantity, Quantity::kForce);
  EXPECT_DOUBLE_EQ(parse_unit("kN")->to_si, 1e3);
}

TEST(Units, UnknownUnitsAreRefused) {
  EXPECT_FALSE(parse_unit("furlong").has_value());
  EXPECT_FALSE(parse_unit("").has_value());
  EXPECT_FALSE(parse_unit("G").has_value());  // not standard gravity: ambiguous
}

// The one table, exposed: every spelling reads as its quantity, and the names listed in
// messages are one per unit in the table's order (a reader's copy of the list lacked micron,
// µm, m/s2 and the other spellings, so a case slip of them was not named).
TEST(Units, SpellingsAndNamesAreTheTableParseUnitReads) {
  for (Quantity q :
       {Quantity::kDisplacement, Quantity::kVelocity, Quantity::kAcceleration, Quantity::kForce}) {
    for (const std::string& s : unit_spellings(q)) {
      const auto u = parse_unit(s);
      ASSERT_TRUE(u.has_value()) << s;
      EXPECT_EQ(u->quantity, q) << s;
    }
  }
  const auto spellings = unit_spellings(Quantity::kDisplacement);
  EXPECT_EQ(spellings, (std::vector<std::string>{"m", "mm", "um", "µm", "micron", "in"}));
  EXPECT_EQ(unit_names(Quantity::kDisplacement), (std::vector<std::string>{"m", "mm", "um", "in"}));
  EXPECT_EQ(unit_names(Quantity::kVelocity),
            (std::vector<std::string>{"m/s", "mm/s", "um/s", "in/s"}));
  EXPECT_EQ(unit_names(Quantity::kAcceleration),
            (std::vector<std::string>{"m/s^2", "mm/s^2", "in/s^2", "g", "mg"}));
  EXPECT_EQ(unit_names(Quantity::kForce), (std::vector<std::string>{"N", "kN", "lbf"}));
  EXPECT_DOUBLE_EQ(parse_unit("n")->to_si, 1.0);  // forces case-blind, as before
  EXPECT_DOUBLE_EQ(parse_unit("KN")->to_si, 1e3);
}

// The list the record readers (CSV, UFF 58, MAT) print with an unknown unit is the table's: it
// was written by hand in each and lacked um/s and in/s^2, which they read.
TEST(Units, KnownUnitsListOneSpellingOfEveryUnitRead) {
  EXPECT_EQ(known_units(),
            "m, mm, um, in, m/s, mm/s, um/s, in/s, m/s^2, mm/s^2, in/s^2, g, mg, N, kN, lbf");
}

TEST(Units, QuantityNamesRoundTrip) {
  for (Quantity q :
       {Quantity::kDisplacement, Quantity::kVelocity, Quantity::kAcceleration, Quantity::kForce}) {
    EXPECT_EQ(parse_quantity(quantity_name(q)), q);
  }
  EXPECT_FALSE(parse_quantity("jerk").has_value());
  EXPECT_EQ(derivative_order(Quantity::kAcceleration), 2);
}

// The commands' and the Python module's one reading of --quantity / --amplitude: a motion, never a
// force, with a message naming the option and the value ('' where none was given).
TEST(Units, MotionQuantitiesAreMotionsNamedByTheirOption) {
  EXPECT_EQ(motion_quantity("--amplitude", "velocity"), Quantity::kVelocity);
  const auto message = [](std::string_view value) {
    try {
      motion_quantity("--quantity", value);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message("force"), "--quantity force: expected displacement, velocity or acceleration");
  EXPECT_EQ(message(""), "--quantity '': expected displacement, velocity or acceleration");
  EXPECT_EQ(message("Velocity"),
            "--quantity Velocity: expected displacement, velocity or acceleration");
}

}  // namespace
}  // namespace jointlab

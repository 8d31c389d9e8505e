#include "jointlab/campaign/campaign.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "jointlab/campaign/steps/iwan_step.h"
#include "jointlab/campaign/steps/known_parameters.h"
#include "jointlab/campaign/steps/linear_step.h"
#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::campaign {
namespace {

namespace fs = std::filesystem;

// The shipped example campaign reads back as written.
TEST(Campaign, ReadsTheExample) {
  const fs::path p =
      fs::path(testing::source_dir()) / "data/examples/riveted-campaign/campaign.toml";
  const Campaign c = read_campaign(p);
  EXPECT_EQ(c.groups.size(), 3u);
  EXPECT_EQ(c.hit_count(), 9);
  ASSERT_EQ(c.channels.size(), 2u);
  EXPECT_EQ(c.channels[1].dof, "9003:3");
  ASSERT_EQ(c.modes.size(), 2u);
  EXPECT_EQ(c.modes[0].band.lo, 100.0);
  EXPECT_EQ(c.modes[0].model_mode, 1);
  EXPECT_EQ(c.modes[0].reference, "acc_9003_z");
  EXPECT_FALSE(c.model.description.empty());
  EXPECT_TRUE(c.linear_update.enabled);
  ASSERT_EQ(c.linear_update.sets.size(), 1u);
  EXPECT_EQ(std::get<double>(c.linear_update.settings.at("mac_threshold").value), 0.5);
  EXPECT_EQ(c.amplitude, Quantity::kVelocity);
  EXPECT_EQ(c.quantity, Quantity::kAcceleration);
  // The Iwan step fits mode 1 only (mode 3 rings while mode 1 slips the rivets).
  EXPECT_TRUE(c.iwan_update.enabled);
  EXPECT_EQ(c.iwan_update.modes, std::vector<std::string>{"mode 1"});
  EXPECT_EQ(c.iwan_update.settings.count("gamma"), 0u);
}

// Each defect names the file and line.
TEST(Campaign, RejectsDefectsNamingTheLine) {
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_campaign_test");
  fs::create_directories(dir);
  std::ofstream(dir / "a.csv") << "# fs: 100\nx\n1\n";
  const fs::path file = dir / "c.toml";
  const std::string head =
      "[[group]]\nname = \"g\"\nfiles = [\"a.csv\"]\n[[channel]]\nname = \"x\"\n";
  EXPECT_NO_THROW(parse_campaign(head + "[[mode]]\nband = [1.0, 2.0]\n", file));
  const auto message = [&](const std::string& text) {
    try {
      parse_campaign(text, file);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(head + "[[mode]]\nband = [2.0, 1.0]\n").find(":7:"), std::string::npos);
  EXPECT_NE(message(head + "[[mode]]\nband = [1.0, 2.0]\nreference = \"y\"\n").find("reference"),
            std::string::npos);
  EXPECT_NE(message(head + "[[mode]]\nband = [1.0, 2.0]\nbogus = 1\n").find("unknown key"),
            std::string::npos);
  EXPECT_NE(message("[[group]]\nname = \"g\"\nfiles = [\"missing.csv\"]\n").find("missing.csv"),
            std::string::npos);
  EXPECT_NE(message(head).find("[[mode]]"), std::string::npos);
  EXPECT_NE(message(head + "[[mode]]\nband = [1.0, 2.0]\n[update.iwan]\nmodes = [\"mode 2\"]\n")
                .find("'mode 2' is not the name of a [[mode]]"),
            std::string::npos);
  // A path the system cannot look up (a name longer than a file name may be) is no file, said
  // with the field, not an uncaught filesystem_error (fuzz_campaign).
  const std::string long_name(300, 'm');
  EXPECT_NE(message(head + "[[mode]]\nband = [1.0, 2.0]\n[model]\nfile = \"" + long_name + "\"\n")
                .find("model: no file"),
            std::string::npos);
  // Two modes of one name: the second is refused at its line.
  EXPECT_NE(message(head + "[[mode]]\nname = \"m\"\nband = [1.0, 2.0]\n[[mode]]\nname = \"m\"\n"
                           "band = [3.0, 4.0]\n")
                .find(":10:"),
            std::string::npos);
  fs::remove_all(dir);
}

// The linear updating options of the command can be set in [update.linear], typed; each bad
// setting is refused at its line with its field named.
TEST(Campaign, LinearUpdateSettingsAreTyped) {
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_campaign_settings");
  fs::create_directories(dir);
  std::ofstream(dir / "a.csv") << "# fs: 100\nx\n1\n";
  std::ofstream(dir / "m.toml") << "# not read here\n";
  const fs::path file = dir / "c.toml";
  // [update.linear] is line 11, its settings from line 13 on (line 13 in the messages).
  const std::string head =
      "[[group]]\nname = \"g\"\nfiles = [\"a.csv\"]\n[[channel]]\nname = \"x\"\ndof = \"0\"\n"
      "[[mode]]\nband = [1.0, 2.0]\n[model]\nfile = \"m.toml\"\n[update.linear]\nsets = "
      "[\"iwan.rivet\", \"spring.kz\"]\n";
  const Campaign c = parse_campaign(head +
                                        "rule = \"smallest\"\nsmallest_set = \"iwan.rivet\"\n"
                                        "tolerance = 0.005\nfrequency_window = 0.3\n"
                                        "alias_mac = 0.95\nmax_iterations = 50\n"
                                        "bounds = { \"spring.kz\" = [1e5, 1e9] }\n"
                                        "trust_signs = true\n",
                                    file);
  const correlate::LinearUpdateOptions lo = linear_update_options(c);
  EXPECT_TRUE(lo.trust_signs);
  EXPECT_EQ(lo.rule, correlate::LinearRule::kSmallest);
  EXPECT_EQ(lo.smallest_set, "iwan.rivet");
  EXPECT_EQ(lo.tolerance, 0.005);
  EXPECT_EQ(lo.frequency_window, 0.3);
  EXPECT_EQ(lo.alias_mac, 0.95);
  EXPECT_EQ(lo.max_iterations, 50);
  ASSERT_EQ(lo.bounds.size(), 1u);
  EXPECT_EQ(lo.bounds[0].name, "spring.kz");
  EXPECT_EQ(lo.bounds[0].lower, 1e5);
  EXPECT_EQ(lo.bounds[0].upper, 1e9);

  // Each defect: the message names the file, the setting's line (13) and the field.
  const auto message = [&](const std::string& setting) {
    try {
      linear_update_options(parse_campaign(head + setting + "\n", file));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string at = file.string() + ":13: ";
  EXPECT_EQ(message("rule = \"fastest\""),
            at + "update.linear.rule must be \"least-squares\" or \"smallest\", not \"fastest\"");
  EXPECT_EQ(message("rule = 1"), at + "update.linear.rule must be a string");
  EXPECT_EQ(message("trust_signs = 1"), at + "update.linear.trust_signs must be true or false");
  EXPECT_EQ(message("rule = true"), at + "update.linear.rule must be a string");
  EXPECT_EQ(message("tolerance = \"small\""), at + "update.linear.tolerance must be a number");
  EXPECT_EQ(message("max_iterations = 2.5"),
            at + "update.linear.max_iterations must be a whole number from 1 to 100000");
  EXPECT_EQ(message("smallest_set = \"iwan.bolt\""),
            at + "update.linear.smallest_set 'iwan.bolt' is not one of update.linear.sets");
  EXPECT_EQ(message("frequency_window = -0.1"),
            at + "update.linear.frequency_window must be >= 0 (0: no window)");
  EXPECT_EQ(message("alias_mac = 1.5"), at + "update.linear.alias_mac must be in (0, 1]");
  EXPECT_EQ(message("bounds = 3.0"),
            at + "update.linear.bounds must be a table of bounds: { \"<set>\" = [lower, upper], "
                 "... }");
  EXPECT_EQ(message("bounds = { \"iwan.bolt\" = [1.0, 2.0] }"),
            at + "update.linear.bounds 'iwan.bolt' is not one of update.linear.sets");
  EXPECT_NE(message("bounds = { \"spring.kz\" = [2.0, 1.0] }")
                .find(":13: update.linear.bounds.\"spring.kz\": need 0 < lower < upper"),
            std::string::npos);
  EXPECT_NE(message("bounds = { \"spring.kz\" = [1.0] }")
                .find(":13: update.linear.bounds.\"spring.kz\" must be [lower, upper]"),
            std::string::npos);
  EXPECT_NE(message("rate = 2").find(":13: update.linear: unknown setting 'rate' (known: rule,"),
            std::string::npos);
  // The smallest rule without a tolerance: the options' own check.
  EXPECT_NE(message("rule = \"smallest\"").find("the smallest rule needs a tolerance > 0"),
            std::string::npos);
  // The Iwan table reads its settings the same way.
  const Campaign iwan =
      parse_campaign(head + "[update.iwan]\nsamples = \"many\"\n", file);  // samples on line 14
  correlate::IwanUpdateOptions io;
  IwanTargetOptions to;
  try {
    iwan_update_options(iwan, io, to);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ":14: update.iwan.samples must be a number");
  }
  // accept_unconfirmed_pairs: true or false, false when not given, refused at its line otherwise.
  // run identifies one Iwan set: a second named in update.iwan sets is refused at its line, not
  // left out without a word (update.linear tunes any number).
  try {
    parse_campaign(head + "[update.iwan]\nsets = [\"iwan.bolt\", \"iwan.rivet\"]\n", file);
    ADD_FAILURE() << "two Iwan sets accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":14: update.iwan.sets names 2 Iwan sets (iwan.bolt, "
                                         "iwan.rivet), but run identifies one"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(accepts_unconfirmed_pairs(parse_campaign(head + "[update.iwan]\n", file)));
  const Campaign accept =
      parse_campaign(head + "[update.iwan]\naccept_unconfirmed_pairs = true\n", file);
  EXPECT_TRUE(accepts_unconfirmed_pairs(accept));
  EXPECT_NO_THROW(iwan_update_options(accept, io, to));
  try {
    iwan_update_options(
        parse_campaign(head + "[update.iwan]\naccept_unconfirmed_pairs = \"yes\"\n", file), io, to);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              file.string() + ":14: update.iwan.accept_unconfirmed_pairs must be true or false");
  }
  fs::remove_all(dir);
}

// A truth file of a model with two Iwan sets gives one table per set; the fitted set's is read
// (before: `missing iwan.Fs`), and without the set named, or naming one it lacks, it is refused
// naming the tables. A flat [iwan] is read whatever the set.
TEST(Campaign, ATruthFileGivesTheFittedSetsTableOfSeveral) {
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_campaign_truth");
  const fs::path two = dir / "two.toml", flat = dir / "flat.toml";
  std::ofstream(two) << "[iwan.bolt]\nKt = 2e7\nFs = 60.0\nchi = -0.4\nbeta = 1.0\n"
                        "[iwan.rivet]\nKt = 8e6\nFs = 40.0\nchi = -0.5\nbeta = 0.5\n"
                        "[scatter]\nKt = 0.02\n";
  std::ofstream(flat) << "[iwan]\nKt = 1.2e7\nFs = 40.0\nchi = -0.4\nbeta = 0.8\n";
  const Truth rivet = read_truth(two, "iwan.rivet");
  EXPECT_EQ(rivet.iwan.Kt, 8e6);
  EXPECT_EQ(rivet.iwan.Fs, 40.0);
  EXPECT_EQ(rivet.iwan.beta, 0.5);
  EXPECT_EQ(rivet.scatter_kt, 0.02);
  EXPECT_EQ(read_truth(two, "bolt").iwan.Fs, 60.0);
  EXPECT_EQ(read_truth(flat, "iwan.bolt").iwan.Kt, 1.2e7);
  const auto message = [](const fs::path& p, const std::string& set) {
    try {
      read_truth(p, set);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(two, "").find("holds the known values of 2 sets (iwan.bolt, iwan.rivet)"),
            std::string::npos);
  EXPECT_NE(message(two, "iwan.nut").find("no [iwan.nut] for the fitted set iwan.nut"),
            std::string::npos);
  // The known values lie in the Iwan element's domain, as a model file's: chi > -1, above 0
  // too (before: any chi read, -1.5 as well).
  const fs::path above = dir / "above.toml", below = dir / "below.toml";
  std::ofstream(above) << "[iwan]\nKt = 1.2e7\nFs = 40.0\nchi = 0.3\nbeta = 0.8\n";
  std::ofstream(below) << "[iwan]\nKt = 1.2e7\nFs = 40.0\nchi = -1.5\nbeta = 0.8\n";
  EXPECT_EQ(read_truth(above).iwan.chi, 0.3);
  EXPECT_EQ(message(below, ""), below.string() + ": iwan: chi = -1.5 must be > -1");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace jointlab::campaign

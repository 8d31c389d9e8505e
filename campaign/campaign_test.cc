#include "jointlab/campaign/campaign.h"

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

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
  EXPECT_EQ(c.linear_update.settings.at("mac_threshold"), 0.5);
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
  // Two modes of one name: the second is refused at its line.
  EXPECT_NE(message(head + "[[mode]]\nname = \"m\"\nband = [1.0, 2.0]\n[[mode]]\nname = \"m\"\n"
                           "band = [3.0, 4.0]\n")
                .find(":10:"),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace jointlab::campaign

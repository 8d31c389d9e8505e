// End-to-end tests of `jointlab simulate`: a labelled two-mass model is struck and the
// written file is a contract test file that `process` reads; bad arguments get one line
// naming the argument, a non-zero exit and no output file.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "jointlab/data/csv_reader.h"
#include "jointlab/tests/cli.h"

namespace jointlab::testing {
namespace {

std::string model_dir() {
  const std::string dir = scratch_dir("simulate_cli");
  write_text(dir + "/M.mtx",
             "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1.0\n2 2 2.0\n");
  write_text(dir + "/K.mtx",
             "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 4.0e6\n2 2 6.0e6\n");
  write_text(dir + "/dofs.csv", "node,component\n9001,3\n9002,3\n");
  write_text(dir + "/model.toml",
             "[matrices]\nmass = \"M.mtx\"\nstiffness = \"K.mtx\"\ndof_labels = \"dofs.csv\"\n"
             "[iwan.j]\nFs = 200.0\nKt = 1.0e6\nchi = -0.5\nbeta = 0.5\n"
             "[[joint]]\na = \"9001:3\"\nb = \"9002:3\"\nelement = \"iwan.j\"\n");
  return dir;
}

TEST(SimulateCli, WritesATestFileThatProcessReads) {
  const std::string dir = model_dir();
  const CommandResult r =
      run_jointlab("simulate " + dir + "/model.toml --impact 9001:3 --force 50 --duration 1 " +
                   "--fs 4000 --sensors 9001:3 1 --noise 1e-4 --seed 3 --out " + dir + "/hit.csv");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("closure error"), std::string::npos) << r.err;
  const data::Record rec = data::read_csv(dir + "/hit.csv");
  EXPECT_EQ(rec.fs, 4000);
  ASSERT_EQ(rec.channels.size(), 2u);
  EXPECT_EQ(rec.channels[0].name, "acc_9001_z");
  EXPECT_EQ(rec.channels[1].name, "acc_9002_z");
  EXPECT_EQ(rec.channels[0].unit, "m/s^2");
  EXPECT_EQ(rec.metadata.at("impact_dof"), "9001:3");
  EXPECT_EQ(rec.metadata.at("force_n"), "50");  // the reader lower-cases keys
  EXPECT_EQ(rec.metadata.at("model"), dir + "/model.toml");
  EXPECT_EQ(rec.size(), 4000);
  const CommandResult p =
      run_jointlab("process " + dir + "/hit.csv --modes 1 --out " + dir + "/backbones");
  EXPECT_EQ(p.status, 0) << p.err;
  EXPECT_TRUE(std::filesystem::exists(dir + "/backbones/hit.acc_9001_z.band1.csv"));
}

TEST(SimulateCli, BadArgumentsGetOneLineAndNoFile) {
  const std::string dir = model_dir();
  const std::string base = "simulate " + dir + "/model.toml --force 50 --duration 1 --fs 4000 ";
  for (const auto& [args, fragment] :
       {std::pair<std::string, std::string>{"--impact 7", "--impact"},
        {"--impact 9003:3", "9003:3"},
        {"--impact 0 --sensors x", "--sensors"},
        {"--impact 0 --pulse 2", "pulse"}}) {
    const std::string out = dir + "/bad.csv";
    const CommandResult r = run_jointlab(base + args + " --out " + out);
    EXPECT_EQ(r.status, 2) << args << ": " << r.err;
    std::string msg = r.err;
    while (!msg.empty() && msg.back() == '\n') msg.pop_back();
    const auto last = msg.rfind('\n');
    const std::string line = last == std::string::npos ? msg : msg.substr(last + 1);
    EXPECT_NE(line.find("error"), std::string::npos) << r.err;
    EXPECT_NE(line.find(fragment), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out)) << args;
  }
}

}  // namespace
}  // namespace jointlab::testing

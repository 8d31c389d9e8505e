// End-to-end tests of `jointlab modes` and `jointlab qsma`: model files written to a
// temporary directory, the built program run on them, its CSV, stderr and exit status
// checked against closed forms and the contract's error rules.
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/model/iwan.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

namespace fs = std::filesystem;
using testing::Close;
constexpr double kTwoPi = 2 * std::numbers::pi;

fs::path dir() { return testing::scratch_folder("model_commands"); }

void write(const std::string& name, const std::string& text) {
  std::ofstream(dir() / name) << text;
}

struct Outcome {
  int status = -1;
  std::string err;
};

// Runs the jointlab program with `args` in the scratch directory.
Outcome run(const std::string& args) {
  const fs::path program =
      fs::absolute(fs::path(jointlab::testing::binary_dir()) / "bin" / "jointlab");
  EXPECT_TRUE(fs::exists(program)) << program << " is not built";
  const fs::path err = dir() / "stderr.txt";
  const std::string command = "cd '" + dir().string() + "' && '" + program.string() + "' " + args +
                              " 2> '" + err.string() + "' > /dev/null";
  const int raw = std::system(command.c_str());
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, testing::read_file(err)};
}

std::vector<std::vector<double>> read_csv(const fs::path& p, std::string* header) {
  std::ifstream in(p);
  std::getline(in, *header);
  std::vector<std::vector<double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      // Text cells (the modes' kind) read as NaN; the tests look at them as text.
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      row.push_back(end != cell.c_str() ? v : std::nan(""));
    }
    rows.push_back(row);
  }
  return rows;
}

const IwanParameters kRivet{40.0, 2.0e6, -0.5, 1.0};
const std::string kIwanTable = "[iwan.rivet]\nFs = 40.0\nKt = 2.0e6\nchi = -0.5\nbeta = 1.0\n";

// A pair of free masses m1, m2 joined by spring k0 (in K) and an Iwan element.
void write_pair(const std::string& stem, double m1, double m2, double k0) {
  write(stem + "_M.mtx", fmt::format("%%MatrixMarket matrix coordinate real symmetric\n"
                                     "2 2 2\n1 1 {:.17g}\n2 2 {:.17g}\n",
                                     m1, m2));
  write(stem + "_K.mtx", fmt::format("%%MatrixMarket matrix array real symmetric\n"
                                     "2 2\n{:.17g}\n{:.17g}\n{:.17g}\n",
                                     k0, -k0, k0));
  write(stem + ".toml", "[matrices]\nmass = \"" + stem + "_M.mtx\"\nstiffness = \"" + stem +
                            "_K.mtx\"\n" + kIwanTable +
                            "\n[[joint]]\na = 0\nb = 1\nelement = \"iwan.rivet\"\n");
}

// Checks every CSV row of a QSMA curve against the closed form of method.md section 3 with
// mass mu. The CSV carries 10 significant digits (rounding 5e-10); 1e-6 is the acceptance.
// With `modal_ratio` Z the model's own damping adds Z to every damping column (method.md
// section 2 point 4) and leaves the frequencies alone.
void expect_closed_form_csv(const fs::path& csv, double k0, double mu, double modal_ratio = 0,
                            const IwanParameters& joint = kRivet) {
  std::string header;
  const auto rows = read_csv(csv, &header);
  EXPECT_EQ(header,
            "force_amplitude,modal_amplitude,frequency_hz,damping_ratio,max_slip,"
            "ringdown_frequency_hz,ringdown_damping_ratio,harmonic_damping_ratio");
  ASSERT_GE(rows.size(), 10u);
  const Iwan iwan(joint);
  for (size_t i = 0; i < rows.size(); ++i) {
    const double x = rows[i][4];
    const double force = k0 * x + iwan.force(x);
    EXPECT_TRUE(Close(rows[i][2], std::sqrt(force / (mu * x)) / kTwoPi, 1e-6)) << i;
    EXPECT_TRUE(Close(rows[i][3], modal_ratio + iwan.dissipation(x) / (kTwoPi * force * x), 1e-6))
        << i;
    EXPECT_TRUE(Close(rows[i][1], std::sqrt(mu) * x, 1e-6)) << i;
    // What a ring-down shows: D / (2 pi x dE/dx), dE/dx = x (k0 + F'(x)) (energy form).
    EXPECT_TRUE(Close(rows[i][6],
                      modal_ratio + iwan.dissipation(x) / (kTwoPi * x * x * (k0 + iwan.tangent(x))),
                      1e-6))
        << i;
    if (i > 0) {
      EXPECT_GT(rows[i][1], rows[i - 1][1]);
    }
  }
}

TEST(ModelCommands, QsmaOfMassOnSpringWithIwanToGround) {
  const double m = 0.5, k0 = 1.0e6;
  write("sdof_M.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 0.5\n");
  write("sdof_K.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1.0e6\n");
  write("sdof.toml", "[matrices]\nmass = \"sdof_M.mtx\"\nstiffness = \"sdof_K.mtx\"\n" +
                         kIwanTable +
                         "\n[[joint]]\na = 0\nb = \"ground\"\nelement = \"iwan.rivet\"\n");
  const Outcome r = run("qsma sdof.toml --mode 1 --points 40 --out sdof.csv");
  EXPECT_EQ(r.status, 0) << r.err;
  expect_closed_form_csv(dir() / "sdof.csv", k0, m);
}

// chi above 0 (method.md: -1 < chi), read from a model file: at chi 0.5 and 2 `modes` gives the
// linear frequency sqrt((k0 + K_T) / m) / 2 pi (10 digits in the file: 1e-9) and `qsma` every
// row of the one-mass closed form (1e-6, as above). Before, both refused the file ("chi = 0.5
// must be in (-1, 0]", exit 2).
TEST(ModelCommands, ModesAndQsmaTakeChiAboveZero) {
  const double m = 0.5, k0 = 1.0e6;
  write("sdofc_M.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 0.5\n");
  write("sdofc_K.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1.0e6\n");
  for (const double chi : {0.5, 2.0}) {
    const IwanParameters p{kRivet.Fs, kRivet.Kt, chi, kRivet.beta};
    write("sdofc.toml", fmt::format("[matrices]\nmass = \"sdofc_M.mtx\"\nstiffness = "
                                    "\"sdofc_K.mtx\"\n[iwan.rivet]\nFs = {}\nKt = {}\nchi = {}\n"
                                    "beta = {}\n\n[[joint]]\na = 0\nb = \"ground\"\nelement = "
                                    "\"iwan.rivet\"\n",
                                    p.Fs, p.Kt, chi, p.beta));
    const Outcome modes = run("modes sdofc.toml --out sdofc_modes.csv");
    ASSERT_EQ(modes.status, 0) << chi << ": " << modes.err;
    std::string header;
    const auto rows = read_csv(dir() / "sdofc_modes.csv", &header);
    ASSERT_EQ(rows.size(), 1u);
    EXPECT_TRUE(Close(rows[0][1], std::sqrt((k0 + p.Kt) / m) / kTwoPi, 1e-9)) << chi;
    const Outcome r = run("qsma sdofc.toml --mode 1 --points 30 --out sdofc.csv");
    ASSERT_EQ(r.status, 0) << chi << ": " << r.err;
    expect_closed_form_csv(dir() / "sdofc.csv", k0, m, 0, p);
  }
}

// [damping] modal_ratio: the closed form plus Z in both damping columns. Z = 3e-3 is of the
// order of the joint damping over the curve (1e-4 .. 1e-1), so a column that missed it, or
// counted it twice, is off by far more than the 1e-6 acceptance at every point.
TEST(ModelCommands, QsmaAddsTheModalDampingRatioToEveryDampingColumn) {
  const double m = 0.5, k0 = 1.0e6, z = 3.0e-3;
  write("sdofz_M.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 0.5\n");
  write("sdofz_K.mtx", "%%MatrixMarket matrix coordinate real general\n1 1 1\n1 1 1.0e6\n");
  write("sdofz.toml", "[matrices]\nmass = \"sdofz_M.mtx\"\nstiffness = \"sdofz_K.mtx\"\n" +
                          kIwanTable + "\n[damping]\nmodal_ratio = 3.0e-3\n" +
                          "\n[[joint]]\na = 0\nb = \"ground\"\nelement = \"iwan.rivet\"\n");
  const Outcome r = run("qsma sdofz.toml --mode 1 --points 40 --out sdofz.csv");
  EXPECT_EQ(r.status, 0) << r.err;
  expect_closed_form_csv(dir() / "sdofz.csv", k0, m, z);
}

TEST(ModelCommands, QsmaOfTwoFreeMassesUsesTheReducedMass) {
  const double m1 = 0.3, m2 = 0.7, k0 = 5.0e5;
  write_pair("pair", m1, m2, k0);
  const Outcome r = run("qsma pair.toml --mode 1 --out pair.csv");
  EXPECT_EQ(r.status, 0) << r.err;
  expect_closed_form_csv(dir() / "pair.csv", k0, m1 * m2 / (m1 + m2));

  const Outcome modes = run("modes pair.toml --out pair_modes.csv");
  EXPECT_EQ(modes.status, 0) << modes.err;
  std::string header;
  const auto rows = read_csv(dir() / "pair_modes.csv", &header);
  EXPECT_EQ(header, "mode,frequency_hz,kind");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0][0], 0.0);
  EXPECT_EQ(rows[0][1], 0.0);
  EXPECT_EQ(rows[1][0], 1.0);
  // 10 significant digits in the file.
  EXPECT_TRUE(
      Close(rows[1][1], std::sqrt((k0 + kRivet.Kt) / (m1 * m2 / (m1 + m2))) / kTwoPi, 1e-9));
  const std::string text = testing::read_file(dir() / "pair_modes.csv");
  EXPECT_NE(text.find(",rigid\n"), std::string::npos);
  EXPECT_NE(text.find(",elastic\n"), std::string::npos);
}

TEST(ModelCommands, QsmaStopsAtTheLimitLoadAndSaysSo) {
  const double m1 = 0.3, m2 = 0.7;
  write_pair("limit", m1, m2, 0.0);
  const Outcome r = run("qsma limit.toml --mode 1 --out limit.csv");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("no static solution past force amplitude"), std::string::npos) << r.err;
  std::string header;
  const auto rows = read_csv(dir() / "limit.csv", &header);
  ASSERT_GE(rows.size(), 2u);
  // alpha_lim = F_S / sqrt(mu), placed within 1 % (the contract; the bracket is 1e-4).
  const double limit = kRivet.Fs / std::sqrt(m1 * m2 / (m1 + m2));
  EXPECT_TRUE(Close(rows.back()[0], limit, 0.01));
  EXPECT_LE(rows.back()[0], limit * (1 + 1e-9));
  expect_closed_form_csv(dir() / "limit.csv", 0.0, m1 * m2 / (m1 + m2));
}

// Each invalid input: exit status 2, one stderr line naming the place, no output left.
TEST(ModelCommands, InvalidModelsFailWithOneClearLine) {
  write_pair("base", 1.0, 2.0, 100.0);
  const std::string mass = "base_M.mtx", stiff = "base_K.mtx";
  auto model = [&](const std::string& m, const std::string& k, const std::string& iwan,
                   const std::string& joint) {
    return "[matrices]\nmass = \"" + m + "\"\nstiffness = \"" + k + "\"\n" + iwan + joint;
  };
  const std::string joint = "\n[[joint]]\na = 0\nb = 1\nelement = \"iwan.rivet\"\n";
  auto iwan_with = [&](const std::string& from, const std::string& to) {
    std::string t = kIwanTable;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  write("nonsym.mtx",
        "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 1\n1 2 1\n2 2 1\n");
  write("nonsquare.mtx", "%%MatrixMarket matrix coordinate real general\n2 3 1\n1 1 1\n");
  write("three.mtx",
        "%%MatrixMarket matrix coordinate real symmetric\n3 3 3\n1 1 1\n2 2 1\n3 3 1\n");
  write("singular.mtx", "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 1 1\n");
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      {"nonsym", model(mass, "nonsym.mtx", kIwanTable, joint),
       "bad_nonsym.toml:3: matrices.stiffness: 'nonsym.mtx' is not symmetric"},
      {"nonsquare", model("nonsquare.mtx", stiff, kIwanTable, joint),
       "bad_nonsquare.toml:2: matrices.mass: 'nonsquare.mtx' is 2 x 3, not square"},
      {"sizes", model(mass, "three.mtx", kIwanTable, joint),
       "matrices.stiffness: 'three.mtx' is 3 x 3 but the mass matrix is 2 x 2"},
      {"range",
       model(mass, stiff, kIwanTable, "\n[[joint]]\na = 0\nb = 2\nelement = \"iwan.rivet\"\n"),
       "joint 1: b = 2 is out of range 0..1"},
      {"element",
       model(mass, stiff, kIwanTable, "\n[[joint]]\na = 0\nb = 1\nelement = \"iwan.bolt\"\n"),
       "joint 1: unknown element 'iwan.bolt'"},
      {"chi", model(mass, stiff, iwan_with("chi = -0.5", "chi = -1.0"), joint),
       "iwan.rivet: chi = -1 must be > -1"},
      {"fs", model(mass, stiff, iwan_with("Fs = 40.0", "Fs = 0.0"), joint),
       "iwan.rivet: Fs = 0 must be > 0"},
      {"kt", model(mass, stiff, iwan_with("Kt = 2.0e6", "Kt = -5.0"), joint),
       "iwan.rivet: Kt = -5 must be > 0"},
      {"beta", model(mass, stiff, iwan_with("beta = 1.0", "beta = -0.5"), joint),
       "iwan.rivet: beta = -0.5 must be >= 0"},
      {"mass", model("singular.mtx", stiff, kIwanTable, joint),
       "matrices.mass: 'singular.mtx' is not positive definite"},
      {"zeta_negative", model(mass, stiff, kIwanTable + "[damping]\nmodal_ratio = -1e-3\n", joint),
       "bad_zeta_negative.toml:10: damping.modal_ratio = -0.001 must be a damping ratio"},
      {"zeta_percent", model(mass, stiff, kIwanTable + "[damping]\nmodal_ratio = 5.0\n", joint),
       "damping.modal_ratio = 5 must be a damping ratio, 0 <= Z < 1"},
      {"zeta_nan", model(mass, stiff, kIwanTable + "[damping]\nmodal_ratio = nan\n", joint),
       "damping.modal_ratio = nan must be a damping ratio"},
      {"zeta_text", model(mass, stiff, kIwanTable + "[damping]\nmodal_ratio = \"low\"\n", joint),
       "damping.modal_ratio must be a number"},
      {"zeta_key", model(mass, stiff, kIwanTable + "[damping]\nratio = 0.01\n", joint),
       "damping: unknown key 'ratio'"},
  };
  for (const Case& c : cases) {
    const std::string file = "bad_" + c.name + ".toml";
    write(file, c.text);
    for (const std::string& command : {std::string("qsma ") + file + " --mode 1 --out bad.csv",
                                       std::string("modes ") + file + " --out bad.csv"}) {
      fs::remove(dir() / "bad.csv");
      const Outcome r = run(command);
      EXPECT_EQ(r.status, 2) << command << "\nstderr: " << r.err;
      EXPECT_NE(r.err.find(c.expected), std::string::npos) << command << "\nstderr: " << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_FALSE(fs::exists(dir() / "bad.csv")) << command;
    }
  }
  // A mode that does not exist.
  const Outcome r = run("qsma base.toml --mode 3 --out bad.csv");
  EXPECT_EQ(r.status, 2);
  // One elastic mode (two free masses: one rigid, one elastic): "1 elastic mode", not "modes".
  EXPECT_NE(r.err.find("mode 3 does not exist: the model has 1 elastic mode (numbered from 1)"),
            std::string::npos)
      << r.err;
}

}  // namespace
}  // namespace jointlab::model

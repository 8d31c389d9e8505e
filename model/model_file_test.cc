#include "jointlab/model/model_file.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::model {
namespace {

namespace fs = std::filesystem;

fs::path dir() {
  const fs::path d = jointlab::testing::scratch_folder("jointlab_model_file_test");
  fs::create_directories(d);
  return d;
}

void write(const std::string& name, const std::string& text) {
  std::ofstream(dir() / name) << text;
}

// Three DOFs: masses 1, 2, 3 kg; springs 100 N/m between 0-1 and 1-2.
const char* kMass = "%%MatrixMarket matrix coordinate real symmetric\n3 3 3\n1 1 1\n2 2 2\n3 3 3\n";
const char* kStiff =
    "%%MatrixMarket matrix array real symmetric\n3 3\n100\n-100\n0\n200\n-100\n100\n";

const std::string kHeader = R"([matrices]
mass = "M.mtx"
stiffness = "K.mtx"
dof_labels = "dofs.csv"

[iwan.rivet]
Fs = 40.0
Kt = 2.0e6
chi = -0.5
beta = 1

[spring]
kz = 5.0e7
)";

void write_matrices() {
  write("M.mtx", kMass);
  write("K.mtx", kStiff);
  write("dofs.csv", "node,component\n1001,1\n1001,2\n1002,1\n");
}

// The InputError message read_model gives for `text` as model file, or "".
std::string error_of(const std::string& text) {
  write_matrices();
  write("bad.toml", text);
  try {
    read_model(dir() / "bad.toml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ModelFile, ReadsMatricesJointsAndLabels) {
  write_matrices();
  write("ok.toml", kHeader + R"(
[[joint]]
a = 0
b = "1002:1"
element = "iwan.rivet"

[[joint]]
a = "1001:2"
b = "ground"
element = "spring.kz"
)");
  const Model m = read_model(dir() / "ok.toml");
  ASSERT_EQ(m.size(), 3);
  ASSERT_EQ(m.joints.size(), 2u);
  EXPECT_EQ(m.joints[0].a, 0);
  EXPECT_EQ(m.joints[0].b, 2);
  ASSERT_TRUE(m.joints[0].iwan.has_value());
  EXPECT_EQ(m.joints[0].iwan->slip_force(), 40.0);
  EXPECT_EQ(m.joints[0].stiffness, 2.0e6);
  EXPECT_EQ(m.joints[1].a, 1);
  EXPECT_EQ(m.joints[1].b, kGround);
  EXPECT_FALSE(m.joints[1].iwan.has_value());
  EXPECT_EQ(m.iwan_count(), 1);
  EXPECT_EQ(m.dof_labels[2], "1002:1");
  EXPECT_EQ(m.mass.coeff(2, 2), 3.0);
  EXPECT_EQ(m.stiffness.coeff(1, 2), -100.0);

  // Eq. 4: Kt [1 -1; -1 1] at (0, 2) and kz at (1, 1); exact sums.
  const Eigen::MatrixXd k = Eigen::MatrixXd(m.linear_stiffness());
  EXPECT_EQ(k(0, 0), 100.0 + 2.0e6);
  EXPECT_EQ(k(2, 2), 100.0 + 2.0e6);
  EXPECT_EQ(k(0, 2), -2.0e6);
  EXPECT_EQ(k(2, 0), -2.0e6);
  EXPECT_EQ(k(1, 1), 200.0 + 5.0e7);
  EXPECT_EQ(k(0, 1), -100.0);
}

TEST(ModelFile, EveryDefectGetsOneLineNamingFileAndField) {
  // kHeader has Fs, Kt, chi, beta on lines 7-10; a joint after it has a, b, element on 16-18.
  const std::string joint = "\n[[joint]]\na = 0\nb = 2\nelement = \"iwan.rivet\"\n";
  struct Case {
    std::string text, expected;
  };
  std::string with_chi = kHeader, with_beta = kHeader, with_fs = kHeader, with_kt = kHeader;
  with_chi.replace(with_chi.find("chi = -0.5"), 10, "chi = -1.0");
  with_beta.replace(with_beta.find("beta = 1"), 8, "beta = -0.5");
  with_fs.replace(with_fs.find("Fs = 40.0"), 9, "Fs = 0.0");
  with_kt.replace(with_kt.find("Kt = 2.0e6"), 10, "Kt = -2.0e6");
  const Case cases[] = {
      {"[matrices\n", "bad.toml:1: TOML syntax"},
      {"[spring]\nk = 1\n", "missing table [matrices]"},
      {with_chi + joint, "bad.toml:9: iwan.rivet: chi = -1 must be > -1"},
      {with_beta + joint, "bad.toml:10: iwan.rivet: beta = -0.5 must be >= 0"},
      {with_fs + joint, "bad.toml:7: iwan.rivet: Fs = 0 must be > 0"},
      {with_kt + joint, "bad.toml:8: iwan.rivet: Kt = -2000000 must be > 0"},
      {kHeader + "\n[[joint]]\na = 0\nb = 3\nelement = \"iwan.rivet\"\n",
       "bad.toml:17: joint 1: b = 3 is out of range 0..2"},
      {kHeader + "\n[[joint]]\na = -1\nb = 2\nelement = \"iwan.rivet\"\n",
       "bad.toml:16: joint 1: a = -1 is out of range 0..2"},
      {kHeader + "\n[[joint]]\na = 0\nb = \"9:9\"\nelement = \"iwan.rivet\"\n",
       "joint 1: b = \"9:9\" is not a label"},
      {kHeader + "\n[[joint]]\na = 0\nb = 2\nelement = \"iwan.bolt\"\n",
       "bad.toml:18: joint 1: unknown element 'iwan.bolt' (defined: iwan.rivet, spring.kz)"},
      {kHeader + "\n[[joint]]\na = 0\nb = 0\nelement = \"spring.kz\"\n",
       "a and b are the same DOF"},
      {kHeader + "\n[[joint]]\na = 0\nelement = \"spring.kz\"\n", "joint 1: 'b' is missing"},
      {kHeader + "\n[spring.kx]\n", "spring.kx must be a number"},
      {kHeader + "kx = -1.0\n", "spring.kx = -1 must be > 0"},
      {kHeader + "\n[sprng]\n", "unknown key 'sprng'"},
  };
  for (const auto& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos)
        << "expected '" << c.expected << "'\nmessage: " << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(ModelFile, MatrixDefectsNameTheMatrixField) {
  const std::string model = "[matrices]\nmass = \"M2.mtx\"\nstiffness = \"K2.mtx\"\n";
  auto error_with = [&](const std::string& m, const std::string& k) {
    write("M2.mtx", m);
    write("K2.mtx", k);
    return error_of(model);
  };
  // Non-symmetric stiffness (general format with K(1,2) != K(2,1)).
  EXPECT_NE(error_with(kMass,
                       "%%MatrixMarket matrix coordinate real general\n3 3 2\n1 2 1\n2 1 "
                       "2\n")
                .find("bad.toml:3: matrices.stiffness: 'K2.mtx' is not symmetric"),
            std::string::npos);
  // Non-square mass.
  EXPECT_NE(error_with("%%MatrixMarket matrix coordinate real general\n3 2 1\n1 1 1\n", kStiff)
                .find("bad.toml:2: matrices.mass: 'M2.mtx' is 3 x 2, not square"),
            std::string::npos);
  // Sizes differ.
  EXPECT_NE(
      error_with("%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 1 1\n2 2 1\n", kStiff)
          .find("matrices.stiffness: 'K2.mtx' is 3 x 3 but the mass matrix is 2 x 2"),
      std::string::npos);
  // Mass not positive definite (a zero diagonal entry).
  EXPECT_NE(
      error_with("%%MatrixMarket matrix coordinate real symmetric\n3 3 2\n1 1 1\n2 2 1\n", kStiff)
          .find("matrices.mass: 'M2.mtx' is not positive definite"),
      std::string::npos);
  // A defect inside the matrix file names that file and line.
  EXPECT_NE(error_with(kMass, "%%MatrixMarket matrix coordinate real symmetric\n3 3 1\n4 1 1\n")
                .find("K2.mtx:3: row index 4 out of range"),
            std::string::npos);
  // Missing matrix file.
  EXPECT_NE(error_of("[matrices]\nmass = \"none.mtx\"\nstiffness = \"K.mtx\"\n").find("none.mtx"),
            std::string::npos);
}

TEST(ModelFile, ValidateModelChecksModelsBuiltInCode) {
  Model m;
  m.mass = Eigen::MatrixXd::Identity(2, 2).sparseView();
  m.stiffness = Eigen::MatrixXd::Identity(2, 2).sparseView();
  m.joints.push_back({0, 1, "spring.k", 10.0, std::nullopt});
  EXPECT_NO_THROW(validate_model(m));
  m.joints.push_back({0, 2, "spring.k", 10.0, std::nullopt});
  EXPECT_THROW(validate_model(m), InputError);
}

}  // namespace
}  // namespace jointlab::model

#include "jointlab/data/abaqus_matrix.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

// Two-node bar (nodes 10 and 20, axial DOF 1 and transverse DOF 2), as *MATRIX OUTPUT,
// FORMAT=MATRIX INPUT writes its lower triangle.
const char* kStiffLower =
    "** Abaqus stiffness, lower triangle\n"
    "10,1, 10,1,  2.000000000000000e+06\n"
    "10,2, 10,2,  5.000000000000000e+05\n"
    "20,1, 10,1, -2.000000000000000e+06\n"
    "20,1, 20,1,  2.000000000000000e+06\n"
    "20,2, 10,2, -5.000000000000000e+05\n"
    "20,2, 20,2,  5.000000000000000e+05\n";

Eigen::MatrixXd expected_k() {
  Eigen::MatrixXd k(4, 4);  // order (10,1) (10,2) (20,1) (20,2)
  k << 2e6, 0, -2e6, 0,     //
      0, 5e5, 0, -5e5,      //
      -2e6, 0, 2e6, 0,      //
      0, -5e5, 0, 5e5;
  return k;
}

TEST(AbaqusMatrix, LowerTriangleBecomesFullSymmetric) {
  const AbaqusMatrix m = parse_abaqus_matrix(kStiffLower, "K.mtx");
  ASSERT_EQ(m.dofs.size(), 4u);
  EXPECT_EQ(m.dofs[0], (DofLabel{10, 1}));
  EXPECT_EQ(m.dofs[3], (DofLabel{20, 2}));
  EXPECT_EQ(Eigen::MatrixXd(m.matrix), expected_k());  // values copied, not computed
}

TEST(AbaqusMatrix, UpperFullAndCoordinateLayouts) {
  const std::string upper =
      "10,1,10,1,2e6\n10,1,20,1,-2e6\n10,2,10,2,5e5\n10,2,20,2,-5e5\n20,1,20,1,2e6\n20,2,20,2,"
      "5e5\n";
  EXPECT_EQ(Eigen::MatrixXd(parse_abaqus_matrix(upper, "u.mtx").matrix), expected_k());
  std::string full = kStiffLower;  // appended, not `string + literal`: GCC 12 -O1 warns wrongly
  full += "10,1,20,1,-2e6\n10,2,20,2,-5e5\n";
  EXPECT_EQ(Eigen::MatrixXd(parse_abaqus_matrix(full, "f.mtx").matrix), expected_k());
  const AbaqusMatrix c = parse_abaqus_matrix("1 1 4.0\n2 1 -1.0\n2 2 4.0\n3 3 1.5\n", "c.mtx");
  ASSERT_EQ(c.dofs.size(), 3u);
  EXPECT_EQ(c.dofs[2], (DofLabel{3, 0}));
  EXPECT_EQ(c.matrix.coeff(0, 1), -1.0);
  EXPECT_EQ(c.matrix.coeff(1, 0), -1.0);
}

TEST(AbaqusMatrix, MassAndStiffnessShareLabelledIndices) {
  const std::filesystem::path dir = testing::scratch_folder("abaqus");
  std::ofstream(dir / "K.mtx") << kStiffLower;
  // Mass only on the translations of node 20 and a node 30 K does not have.
  std::ofstream(dir / "M.mtx") << "20,1,20,1,0.5\n20,2,20,2,0.5\n30,1,30,1,0.25\n";
  const AbaqusModel m = read_abaqus_model(dir / "M.mtx", dir / "K.mtx");
  ASSERT_EQ(m.dofs.size(), 5u);
  EXPECT_EQ(m.dofs[4], (DofLabel{30, 1}));
  EXPECT_EQ(m.mass.coeff(2, 2), 0.5);
  EXPECT_EQ(m.mass.coeff(4, 4), 0.25);
  EXPECT_EQ(m.stiffness.coeff(0, 2), -2e6);
  EXPECT_EQ(m.stiffness.coeff(4, 4), 0.0);
  EXPECT_EQ(m.mass.rows(), 5);
  EXPECT_EQ(m.stiffness.rows(), 5);
}

TEST(AbaqusMatrixBadInput, EachDefectIsOneLineNamingFileAndLine) {
  struct Case {
    std::string text, fragment;
  };
  const Case cases[] = {
      {"", "m.mtx: no matrix entries"},
      {"1,1,1,1\n", "m.mtx:1: 4 fields"},
      {"1,1,1,1,2\n1,1,3\n", "m.mtx:2: 3 fields after lines of 5"},
      {"1,1,1,1,nan\n", "m.mtx:1: value nan (NaN and Inf"},
      {"1,1,1,1,inf\n", "m.mtx:1: value inf"},
      {"1,1,1,1,abc\n", "m.mtx:1: value 'abc' is not a number"},
      {"1,x,1,1,2\n", "m.mtx:1: field 2 'x' is not an integer"},
      {"1,0,1,1,2\n", "m.mtx:1: field 2: DOF 0"},
      {"0 1 2\n", "m.mtx:1: field 1: equation number 0"},
      {"1,1,1,1,2\n1,1,1,1,3\n", "m.mtx:2: entry (1:1, 1:1) given twice (first at line 1)"},
      {"1,1,2,1,1\n2,1,1,1,2\n", "is not symmetric"},
      {"99999999999999999999,1,1,1,2\n", "m.mtx:1: field 1"},
  };
  for (const Case& c : cases) {
    const std::string m = testing::input_error_of([&] { parse_abaqus_matrix(c.text, "m.mtx"); });
    EXPECT_NE(m.find(c.fragment), std::string::npos) << "text: " << c.text << "\nmessage: " << m;
  }
  EXPECT_THROW(read_abaqus_matrix("/nonexistent/K.mtx"), InputError);
}

}  // namespace
}  // namespace jointlab::data

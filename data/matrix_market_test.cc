#include "jointlab/data/matrix_market.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

namespace fs = std::filesystem;

constexpr const char* kScratch = "jointlab-matrix-market-test";

fs::path scratch(const std::string& name, const std::string& text) {
  return testing::scratch_file(kScratch, name, text);
}

// The error message of read_matrix_market on `text`, or "" if it reads.
std::string error_of(const std::string& text) {
  try {
    read_matrix_market(scratch("bad.mtx", text));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// An entry of a matrix and the value it must hold.
struct Entry {
  int row, col;
  double value;
};

// Every entry of `expected` in m, exactly (the files hold short decimals).
void expect_entries(const Eigen::SparseMatrix<double>& m, const std::vector<Entry>& expected) {
  for (const Entry& e : expected) {
    EXPECT_EQ(m.coeff(e.row, e.col), e.value) << "(" << e.row << ", " << e.col << ")";
  }
}

TEST(MatrixMarket, ReadsCoordinateGeneral) {
  const auto m = read_matrix_market(scratch("g.mtx",
                                            "%%MatrixMarket matrix coordinate real general\n"
                                            "% a comment\n"
                                            "2 3 3\n"
                                            "1 1 1.5\n"
                                            "2 3 -2e3\n"
                                            "1 1 0.5\n"));  // duplicates are summed
  ASSERT_EQ(m.rows(), 2);
  ASSERT_EQ(m.cols(), 3);
  EXPECT_EQ(m.coeff(0, 0), 2.0);
  EXPECT_EQ(m.coeff(1, 2), -2000.0);
  EXPECT_EQ(m.coeff(0, 2), 0.0);
}

TEST(MatrixMarket, ReadsCoordinateSymmetricMirrored) {
  const auto m = read_matrix_market(scratch("s.mtx",
                                            "%%MatrixMarket matrix coordinate real symmetric\r\n"
                                            "3 3 4\r\n1 1 2\r\n2 1 -1\r\n2 2 2\r\n3 3 +1\r\n"));
  EXPECT_EQ(m.coeff(0, 1), -1.0);
  EXPECT_EQ(m.coeff(1, 0), -1.0);
  EXPECT_EQ(m.coeff(2, 2), 1.0);
  EXPECT_EQ(m.nonZeros(), 5);
}

TEST(MatrixMarket, ReadsArrayGeneralAndSymmetric) {
  // Column-major: [[1 3] [2 4]].
  const auto g = read_matrix_market(
      scratch("a.mtx", "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n"));
  expect_entries(g, {{0, 0, 1.0}, {1, 0, 2.0}, {0, 1, 3.0}, {1, 1, 4.0}});
  // Lower triangle column by column: a11 a21 a31 a22 a32 a33.
  const auto s = read_matrix_market(
      scratch("as.mtx", "%%MatrixMarket matrix array real symmetric\n3 3\n1\n2\n3\n4\n5\n6\n"));
  expect_entries(s, {{0, 2, 3.0}, {2, 0, 3.0}, {2, 1, 5.0}, {1, 2, 5.0}, {2, 2, 6.0}});
}

TEST(MatrixMarket, WriteReadRoundTripIsExact) {
  Eigen::SparseMatrix<double> m(3, 3);
  m.insert(0, 0) = 1.0 / 3.0;
  m.insert(1, 0) = -2.0e-17;
  m.insert(0, 1) = -2.0e-17;
  m.insert(2, 2) = 6.02214076e23;
  m.insert(2, 1) = 0.1;
  m.insert(1, 2) = 0.1;
  for (bool symmetric : {true, false}) {
    const fs::path p = testing::scratch_path(kScratch, symmetric ? "rs.mtx" : "rg.mtx");
    write_matrix_market(p, m, symmetric);
    const auto r = read_matrix_market(p);
    // 17 significant digits reproduce every double exactly.
    EXPECT_EQ((Eigen::MatrixXd(r) - Eigen::MatrixXd(m)).cwiseAbs().maxCoeff(), 0.0);
  }
  std::ifstream in(testing::scratch_path(kScratch, "rs.mtx"));
  std::string banner, size;
  std::getline(in, banner);
  std::getline(in, size);
  EXPECT_EQ(banner, "%%MatrixMarket matrix coordinate real symmetric");
  EXPECT_EQ(size, "3 3 4");  // lower triangle only
}

TEST(MatrixMarket, DefectsNameFileAndLine) {
  const std::string co = "%%MatrixMarket matrix coordinate real general\n";
  struct Case {
    std::string text, expected;
  };
  const Case cases[] = {
      {"", "bad.mtx: empty file"},
      {"hello\n", "bad.mtx:1: expected banner"},
      {"%%MatrixMarket matrix coordinate complex general\n2 2 0\n", ":1: field 'complex'"},
      {"%%MatrixMarket matrix coordinate real hermitian\n2 2 0\n", ":1: symmetry 'hermitian'"},
      {co + "% c\n2 2 1\n3 1 1.0\n", ":4: row index 3 out of range 1..2"},
      {co + "2 2 1\n1 0 1.0\n", ":3: column index 0 out of range"},
      {co + "2 2 2\n1 1 1.0\n", "file ends after 1 of 2 entries"},
      {co + "2 2 1\n1 1 1.0\n2 2 1.0\n", ":4: more entries than the size line"},
      {co + "2 2 1\n1 1 abc\n", ":3: value 'abc' is not a number"},
      {co + "2 2 1\n1 1 nan\n", ":3: value 'nan' is not finite"},
      {co + "2 2\n", ":2: size line must be 'rows cols entries'"},
      {"%%MatrixMarket matrix coordinate real symmetric\n2 3 0\n",
       ":2: symmetric matrix must be square"},
      {"%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 2 1\n",
       ":3: entry (1, 2) above the diagonal"},
      {"%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n",
       "file ends before every array value"},
      // Sizes are checked before anything is allocated (each entry line takes 6 bytes or
      // more, an array value 2; the file below is 70 bytes).
      {co + "2 2 1000000000000\n1 1 1\n",
       ":2: size line declares 1000000000000 entries; the file's 70 bytes hold at most 11"},
      {"%%MatrixMarket matrix array real general\n100000 100000\n1\n",
       ":2: size 100000 x 100000 needs 10000000000 values; the file's"},
      {co + "3000000000 3000000000 0\n", ":2: size 3000000000 x 3000000000 exceeds the limit"},
      {co + "2 2 1\n1 1 " + std::string(100000, '9') + "x\n", "... (100001 bytes)"},
  };
  for (const auto& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_NE(message.find(c.expected), std::string::npos) << "input:\n"
                                                           << c.text << "\nmessage: " << message;
    EXPECT_NE(message.find("bad.mtx"), std::string::npos) << message;
  }
  EXPECT_THROW(read_matrix_market("/nonexistent/dir/m.mtx"), InputError);
}

TEST(MatrixMarket, DimensionLimitOfTheCaller) {
  const fs::path p = scratch("big.mtx",
                             "%%MatrixMarket matrix coordinate real general\n"
                             "2000000000 2000000000 1\n1 1 1\n");
  const std::string m = testing::input_error_of([&] { read_matrix_market(p, 1000); });
  EXPECT_NE(m.find("big.mtx:2: size 2000000000 x 2000000000 exceeds the limit of 1000 rows and "
                   "columns"),
            std::string::npos)
      << m;
  EXPECT_EQ(read_matrix_market(scratch("ok.mtx",
                                       "%%MatrixMarket matrix coordinate real general\n"
                                       "1000 1000 1\n1 1 1\n"),
                               1000)
                .rows(),
            1000);
}

}  // namespace
}  // namespace jointlab::data

#include "jointlab/data/mat_file.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <matio.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

using jointlab::testing::Close;
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return testing::scratch_path("jointlab-mat-test", name);
}

// Writes top-level variables (column vectors of doubles, or char rows) with matio directly.
struct Var {
  std::string name;
  std::vector<double> values;
  std::string text;  // a char row when values is empty
};

void write_vars(const fs::path& path, const std::vector<Var>& vars, const std::string& in_struct) {
  mat_t* mat = Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5);
  ASSERT_NE(mat, nullptr);
  std::vector<matvar_t*> made;
  for (const Var& v : vars) {
    size_t dims[2] = {v.values.size(), 1};
    if (v.values.empty()) {
      dims[0] = 1;
      dims[1] = v.text.size();
      made.push_back(Mat_VarCreate(v.name.c_str(), MAT_C_CHAR, MAT_T_UTF8, 2, dims,
                                   const_cast<char*>(v.text.data()), 0));
    } else {
      made.push_back(Mat_VarCreate(v.name.c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims,
                                   const_cast<double*>(v.values.data()), 0));
    }
  }
  if (in_struct.empty()) {
    for (matvar_t* m : made) {
      Mat_VarWrite(mat, m, MAT_COMPRESSION_NONE);
      Mat_VarFree(m);
    }
  } else {
    std::vector<const char*> names;
    for (const Var& v : vars) names.push_back(v.name.c_str());
    names.push_back(nullptr);
    size_t one[2] = {1, 1};
    matvar_t* st = Mat_VarCreateStruct2(in_struct.c_str(), 2, one, names.data());
    for (size_t i = 0; i < made.size(); ++i) Mat_VarSetStructFieldByIndex(st, i, 0, made[i]);
    Mat_VarWrite(mat, st, MAT_COMPRESSION_ZLIB);
    Mat_VarFree(st);
  }
  Mat_Close(mat);
}

std::vector<double> ramp(int n, double a, double b) {
  std::vector<double> v(n);
  for (int k = 0; k < n; ++k) v[k] = a + b * k;
  return v;
}

TEST(MatFile, HammerImpactReadsAsThreeAccelerationChannels) {
  const fs::path file = fs::path(jointlab::testing::source_dir()) /
                        "../shared/data/brake-reuss-beam/HammerImpact.mat";
  if (!fs::exists(file)) GTEST_SKIP() << "HammerImpact.mat not found beside the repository";
  const Record r = read_mat(file);
  ASSERT_EQ(r.channels.size(), 3u);
  const char* names[] = {"acc1", "acc2", "acc3"};
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(r.channels[c].name, names[c]);
    ASSERT_TRUE(r.channels[c].quantity.has_value());
    EXPECT_EQ(*r.channels[c].quantity, Quantity::kAcceleration);
    EXPECT_EQ(r.channels[c].unit, "m/s^2");
  }
  EXPECT_EQ(r.size(), 65536);
  // fs = 1 / mean step of a time vector printed by MATLAB in doubles: 1e-9 is far above
  // its rounding and far below any other plausible rate.
  EXPECT_TRUE(Close(r.fs, 12800.0, 1e-9)) << r.fs;
  EXPECT_TRUE(Close(r.t0, -0.01, 1e-12));
  EXPECT_EQ(r.metadata.at("format"), "mat-v5");
}

TEST(MatFile, V73IsSupportedHere) {
  // matio 1.5.23 in Debian 12 is built with HDF5: writing and reading v7.3 both work.
  EXPECT_TRUE(mat_v73_supported());
}

void expect_round_trip(MatVersion version) {
  Record r;
  r.fs = 3000.0;  // 1/fs is not a binary fraction: fs is stored, not derived from time
  r.t0 = -0.0123;
  Eigen::VectorXd x(5);
  x << 1.0 / 3.0, -2.5e-7, 123456.789012345678, 0.0, std::acos(-1.0);
  r.channels.push_back(Channel{"acc1", Quantity::kAcceleration, "m/s^2", x});
  r.channels.push_back(Channel{"1+Z", Quantity::kForce, "N", -x});
  r.channels.push_back(Channel{"mic", std::nullopt, "", 2 * x});
  const fs::path file = scratch(version == MatVersion::kV5 ? "rt5.mat" : "rt73.mat");
  write_mat(file, r, version);
  const Record back = read_mat(file);
  EXPECT_EQ(back.fs, r.fs);
  EXPECT_EQ(back.t0, r.t0);
  ASSERT_EQ(back.channels.size(), 3u);
  for (size_t c = 0; c < 3; ++c) {
    EXPECT_EQ(back.channels[c].name, r.channels[c].name);
    EXPECT_EQ(back.channels[c].quantity, r.channels[c].quantity);
    EXPECT_EQ(back.channels[c].samples, r.channels[c].samples);  // doubles: bit for bit
  }
  EXPECT_EQ(back.metadata.at("format"), version == MatVersion::kV5 ? "mat-v5" : "mat-v7.3");
}

TEST(MatFile, WrittenV5ReadsBackEqual) { expect_round_trip(MatVersion::kV5); }

TEST(MatFile, WrittenV73ReadsBackEqual) {
  if (!mat_v73_supported()) GTEST_SKIP() << "matio here has no HDF5";
  expect_round_trip(MatVersion::kV73);
}

TEST(MatFile, TopLevelVariablesWithFsAndUnits) {
  const fs::path file = scratch("top.mat");
  write_vars(file,
             {{"fs", {2048.0}, ""},
              {"x", ramp(8, 0, 1), ""},
              {"f", ramp(8, 1, -0.5), ""},
              {"units", {}, "mm, N"},
              {"test", {}, "run 3"}},
             "");
  const Record r = read_mat(file);
  EXPECT_EQ(r.fs, 2048.0);
  EXPECT_EQ(r.t0, 0.0);
  ASSERT_EQ(r.channels.size(), 2u);
  EXPECT_EQ(*r.channels[0].quantity, Quantity::kDisplacement);
  EXPECT_DOUBLE_EQ(r.channels[0].samples[3], 3e-3);  // mm -> m
  EXPECT_EQ(*r.channels[1].quantity, Quantity::kForce);
  EXPECT_EQ(r.metadata.at("test"), "run 3");
}

// A file written by another program: scipy.io.savemat (Debian python3-scipy), at test time.
TEST(MatFile, ReadsWhatScipyWrites) {
  std::string python;
  for (const char* p : {"/usr/bin/python3", "python3"}) {
    if (std::system(fmt::format("{} -c 'import scipy.io' >/dev/null 2>&1", p).c_str()) == 0) {
      python = p;
      break;
    }
  }
  if (python.empty()) GTEST_SKIP() << "python3 with scipy not available";
  const fs::path file = scratch("scipy.mat");
  const fs::path script = scratch("write.py");
  std::ofstream(script) << "import numpy as np, scipy.io, sys\n"
                           "t = -0.01 + np.arange(1000) / 12800.0\n"
                           "a = np.sin(2 * np.pi * 80.5 * t)\n"
                           "scipy.io.savemat(sys.argv[1], {'HIdata': {'time': t, 'acc1': a,"
                           " 'acc2': (2 * a).astype(np.float32), 'units': 's, g'}},"
                           " do_compression=True)\n";
  ASSERT_EQ(std::system(fmt::format("{} {} {}", python, script.string(), file.string()).c_str()),
            0);
  const Record r = read_mat(file);
  ASSERT_EQ(r.channels.size(), 2u);
  EXPECT_TRUE(Close(r.fs, 12800.0, 1e-9));
  EXPECT_TRUE(Close(r.t0, -0.01, 1e-15));
  EXPECT_EQ(*r.channels[0].quantity, Quantity::kAcceleration);
  for (int k = 0; k < 1000; ++k) {
    const double t = -0.01 + k / 12800.0;
    const double a = std::sin(2 * std::numbers::pi * 80.5 * t);
    // float64 sine from numpy vs libm: a few ulps; float32 copy: 6e-8 relative.
    ASSERT_TRUE(Close(r.channels[0].samples[k], 9.80665 * a, 0, 1e-12)) << k;
    ASSERT_TRUE(Close(r.channels[1].samples[k], 2 * 9.80665 * a, 0, 2e-6)) << k;
  }
}

// The hostile-input list.
TEST(MatFileBadInput, NoTimeBase) {
  const fs::path file = scratch("notime.mat");
  write_vars(file, {{"x", ramp(8, 0, 1), ""}}, "s");
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m.find(file.string() + ": no time histories found"), std::string::npos) << m;
}

TEST(MatFileBadInput, ZeroSamplingRate) {
  const fs::path file = scratch("fs0.mat");
  write_vars(file, {{"fs", {0.0}, ""}, {"x", ramp(8, 0, 1), ""}}, "s");
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m.find(": field 's.fs': 0 Hz is not a positive sampling rate"), std::string::npos) << m;
}

TEST(MatFileBadInput, NanAndInfSamples) {
  const fs::path file = scratch("nan.mat");
  std::vector<double> x = ramp(8, 0, 1);
  x[5] = NAN;
  write_vars(file, {{"time", ramp(8, 0, 0.1), ""}, {"x", x, ""}}, "s");
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m.find(": field 's.x': sample 6 is nan"), std::string::npos) << m;
  x[5] = INFINITY;
  write_vars(file, {{"time", ramp(8, 0, 0.1), ""}, {"x", x, ""}}, "");
  const std::string m2 = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m2.find(": field 'x': sample 6 is inf"), std::string::npos) << m2;
}

TEST(MatFileBadInput, NonMonotonicTime) {
  const fs::path file = scratch("back.mat");
  std::vector<double> t = ramp(8, 0, 0.1);
  std::swap(t[3], t[4]);
  write_vars(file, {{"time", t, ""}, {"x", ramp(8, 0, 1), ""}}, "rec");
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m.find("at sample 5 does not increase (previous 0.4)"), std::string::npos) << m;
}

TEST(MatFileBadInput, DuplicateChannelNames) {
  // Two channels named alike through jointlab's channel_names cell.
  Record r;
  r.fs = 10;
  r.channels.push_back(Channel{"a b", std::nullopt, "", Eigen::VectorXd::Ones(3)});
  r.channels.push_back(Channel{"a_b", std::nullopt, "", Eigen::VectorXd::Ones(3)});
  const fs::path file = scratch("dup.mat");
  write_mat(file, r);  // fields a_b and a_b_2: distinct
  EXPECT_EQ(read_mat(file).channels[1].name, "a_b");
  // Now make the names collide: rewrite the file with two equal names.
  mat_t* mat = Mat_CreateVer(file.c_str(), nullptr, MAT_FT_MAT5);
  ASSERT_NE(mat, nullptr);
  const char* fields[] = {"fs", "x", "y", "channel_names", nullptr};
  size_t one[2] = {1, 1}, two[2] = {2, 1}, three[2] = {3, 1}, len[2] = {1, 1};
  matvar_t* st = Mat_VarCreateStruct2("s", 2, one, fields);
  double fsv = 10, xs[3] = {1, 2, 3};
  Mat_VarSetStructFieldByName(st, "fs", 0,
                              Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, one, &fsv, 0));
  Mat_VarSetStructFieldByName(st, "x", 0,
                              Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, three, xs, 0));
  Mat_VarSetStructFieldByName(st, "y", 0,
                              Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, three, xs, 0));
  char q[] = "q";
  matvar_t* cells[2] = {Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, len, q, 0),
                        Mat_VarCreate(nullptr, MAT_C_CHAR, MAT_T_UTF8, 2, len, q, 0)};
  Mat_VarSetStructFieldByName(st, "channel_names", 0,
                              Mat_VarCreate(nullptr, MAT_C_CELL, MAT_T_CELL, 2, two, cells, 0));
  Mat_VarWrite(mat, st, MAT_COMPRESSION_NONE);
  Mat_VarFree(st);
  Mat_Close(mat);
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m.find(": field 's.y': two channels named 'q'"), std::string::npos) << m;
}

TEST(MatFileBadInput, TruncatedFile) {
  Record r;
  r.fs = 10;
  r.channels.push_back(Channel{"a", Quantity::kAcceleration, "", Eigen::VectorXd::Ones(1000)});
  const fs::path file = scratch("trunc.mat");
  write_mat(file, r);
  fs::resize_file(file, fs::file_size(file) / 2);
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_EQ(m.rfind(file.string() + ": ", 0), 0u) << m;
  EXPECT_NE(m.find(": not a valid MATLAB v5 file: element of type 15 declares"), std::string::npos)
      << m;
}

// A hand-made v5 file whose one variable, "time", declares 2e9 x 1000 doubles in 16 bytes.
TEST(MatFileBadInput, HugeDeclaredSize) {
  std::string bytes(116, ' ');
  bytes.replace(0, 19, "MATLAB 5.0 MAT-file");
  bytes += std::string(8, '\0');
  bytes += std::string("\x00\x01IM", 4);
  auto u32 = [&](uint32_t v) { bytes.append(reinterpret_cast<const char*>(&v), 4); };
  u32(14);  // miMATRIX
  u32(72);
  u32(6), u32(8), u32(6), u32(0);                           // array flags: mxDOUBLE_CLASS
  u32(5), u32(8), u32(2000000000u), u32(1000);              // dimensions
  u32(1), u32(4), bytes += std::string("time\0\0\0\0", 8);  // name
  u32(9), u32(16), bytes += std::string(16, '\0');          // real part: 16 bytes only
  const fs::path file = scratch("huge.mat");
  std::ofstream(file, std::ios::binary) << bytes;
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_EQ(m.rfind(file.string() + ": ", 0), 0u) << m;
}

TEST(MatFileBadInput, NotAMatFile) {
  const fs::path file = scratch("text.mat");
  std::ofstream(file) << std::string(200, 'x');
  const std::string m = testing::input_error_of([&] { read_mat(file); });
  EXPECT_NE(m.find("not a MATLAB v5/v7/v7.3 .mat file"), std::string::npos) << m;
}

// Inputs the fuzzer found (fuzz/regressions/mat/): each must be a one-line InputError.
TEST(MatFileBadInput, FuzzRegressions) {
  const fs::path dir = fs::path(jointlab::testing::source_dir()) / "fuzz/regressions/mat";
  ASSERT_TRUE(fs::is_directory(dir)) << dir;
  int count = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string m = testing::input_error_of([&] { read_mat(entry.path()); });
    EXPECT_EQ(m.rfind(entry.path().string() + ": ", 0), 0u) << m;
    ++count;
  }
  EXPECT_GT(count, 0);
}

}  // namespace
}  // namespace jointlab::data

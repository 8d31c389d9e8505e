#include "jointlab/data/read_record.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/mat_file.h"
#include "jointlab/data/record_writer.h"
#include "jointlab/data/uff58.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return testing::scratch_path("jointlab-read-record", name);
}

Record sample() {
  Record r;
  r.fs = 1000;
  r.channels.push_back(
      Channel{"acc1", Quantity::kAcceleration, "m/s^2", Eigen::VectorXd::LinSpaced(10, -1, 1)});
  return r;
}

TEST(ReadRecord, DispatchesByExtension) {
  write_csv_record(scratch("a.csv"), sample());
  write_uff58(scratch("a.uff"), sample(), true);
  write_mat(scratch("a.mat"), sample());
  EXPECT_EQ(detect_format(scratch("a.csv")), FileFormat::kCsv);
  EXPECT_EQ(detect_format(scratch("a.uff")), FileFormat::kUff58);
  EXPECT_EQ(detect_format(scratch("a.mat")), FileFormat::kMat);
  for (const char* name : {"a.csv", "a.uff", "a.mat"}) {
    const Record r = read_record(scratch(name));
    ASSERT_EQ(r.channels.size(), 1u) << name;
    EXPECT_EQ(r.channels[0].samples, sample().channels[0].samples) << name;
    EXPECT_EQ(r.fs, 1000.0) << name;
  }
}

TEST(ReadRecord, DispatchesByContentWhenTheExtensionSaysNothing) {
  write_uff58(scratch("u.dat"), sample(), false);
  write_mat(scratch("m.bin"), sample());
  write_mat(scratch("m73.bin"), sample(), MatVersion::kV73);
  EXPECT_EQ(detect_format(scratch("u.dat")), FileFormat::kUff58);
  EXPECT_EQ(detect_format(scratch("m.bin")), FileFormat::kMat);
  EXPECT_EQ(detect_format(scratch("m73.bin")), FileFormat::kMat);
  EXPECT_EQ(read_record(scratch("m73.bin")).size(), 10);
}

TEST(ReadRecord, ExamplesFromOtherPrograms) {
  const fs::path dir = fs::path(jointlab::testing::source_dir()) / "data/examples/uff58";
  EXPECT_EQ(read_record(dir / "Sample_UFF58b_bin.uff").size(), 79292);
  const fs::path hammer = fs::path(jointlab::testing::source_dir()) /
                          "../shared/data/brake-reuss-beam/HammerImpact.mat";
  if (!fs::exists(hammer)) GTEST_SKIP() << "HammerImpact.mat not found beside the repository";
  EXPECT_EQ(read_record(hammer).channels.size(), 3u);
}

TEST(ReadRecord, UnknownFormatIsOneLineNamingTheFile) {
  const fs::path f = scratch("notes.docx");
  std::ofstream(f) << "hello";
  try {
    read_record(f);
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos);
    EXPECT_EQ(m.rfind(f.string() + ": unknown file format (extension '.docx'", 0), 0u) << m;
  }
  EXPECT_THROW(read_record(scratch("missing.csv")), InputError);
}

}  // namespace
}  // namespace jointlab::data

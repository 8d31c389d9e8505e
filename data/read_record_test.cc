#include "jointlab/data/read_record.h"

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/mat_file.h"
#include "jointlab/data/names.h"
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

// The message of the InputError that reading `path` throws, or "" if it reads.
std::string read_error(const fs::path& path) {
  try {
    read_record(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// Output files are named after channels, so every reader refuses a name longer than
// kMaxChannelNameBytes, naming the file and the length, and reads one at the limit.
TEST(ReadRecord, LongChannelNamesAreRefusedByEveryReader) {
  for (const size_t bytes : {kMaxChannelNameBytes, kMaxChannelNameBytes + 1, size_t{5000}}) {
    SCOPED_TRACE(bytes);
    const std::string name(bytes, 'n');
    Record r = sample();
    r.channels[0].name = name;
    write_csv_record(scratch("long.csv"), r);
    write_mat(scratch("long.mat"), r);
    // The UFF writer keeps to 80 characters; ID line 1 is the name, so lengthen it in the text.
    r.channels[0].name = "placeholder_name";
    write_uff58(scratch("long.uff"), r, false);
    std::stringstream text;
    text << std::ifstream(scratch("long.uff")).rdbuf();
    std::string uff = text.str();
    uff.replace(uff.find("placeholder_name"), 16, name);
    std::ofstream(scratch("long.uff")) << uff;
    for (const char* file : {"long.csv", "long.mat", "long.uff"}) {
      const std::string m = read_error(scratch(file));
      if (bytes <= kMaxChannelNameBytes) {
        EXPECT_EQ(m, "") << file;
        EXPECT_EQ(read_record(scratch(file)).channels.at(0).name, name) << file;
        continue;
      }
      EXPECT_NE(m.find(scratch(file).string()), std::string::npos) << m;
      EXPECT_NE(m.find(fmt::format("channel name of {} bytes ('nnnnnnnnnn", bytes)),
                std::string::npos)
          << m;
      EXPECT_NE(m.find("'): at most 128 (names make output file names)"), std::string::npos) << m;
      EXPECT_LT(m.size(), 300u) << file;
    }
  }
}

// Two names that differ only in bytes that are not UTF-8 (or in '/' and control characters)
// would name the same output file: refused, naming both.
TEST(ReadRecord, NamesGivingTheSameFileNameAreRefused) {
  EXPECT_EQ(file_name_part("acc\xff\xfe"), "acc__");
  EXPECT_EQ(file_name_part(std::string("a/b\x01\x7f", 5) + std::string(1, '\0') + "c"), "a_b___c");
  EXPECT_EQ(file_name_part("caf\xc3\xa9 \xe2\x82\xac"),
            "caf\xc3\xa9 \xe2\x82\xac");             // valid UTF-8 stays
  EXPECT_EQ(file_name_part("\xc3"), "_");            // truncated sequence
  EXPECT_EQ(file_name_part("\xed\xa0\x80"), "___");  // a surrogate
  EXPECT_EQ(file_name_part("\xc0\xaf"), "__");       // an overlong '/'
  Record r = sample();
  r.channels.push_back(r.channels[0]);
  r.channels[0].name = "acc\xff";
  r.channels[1].name = "acc\xfe";
  write_csv_record(scratch("twins.csv"), r);
  const std::string m = read_error(scratch("twins.csv"));
  EXPECT_NE(m.find("channels 'acc?' and 'acc?' both make output file names with 'acc_'"),
            std::string::npos)
      << m;
}

TEST(ReadRecord, FilesWhoseStemsMakeTheSameOutputNameAreRefused) {
  // process and stepped-sine name outputs after the stems: a/hit.csv and b/hit.uff, or stems
  // that differ only in bytes file_name_part replaces, would write the same files.
  EXPECT_NO_THROW(check_distinct_stems({"a/hit1.csv", "a/hit2.csv", "hit3.mat"}));
  try {
    check_distinct_stems({"a/hit.csv", "b/x.csv", "b/hit.uff"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "a/hit.csv and b/hit.uff share the name 'hit': outputs would collide");
  }
  EXPECT_THROW(check_distinct_stems({"acc\xff.csv", "acc\xfe.csv"}), InputError);
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

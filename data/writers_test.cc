#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>

#include "jointlab/data/atomic_file.h"
#include "jointlab/data/json_writer.h"
#include "jointlab/data/table_writer.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  return testing::scratch_path("jointlab-writers-test", name);
}

TEST(AtomicFile, UncommittedLeavesNothing) {
  const fs::path p = scratch("never.txt");
  fs::remove(p);
  {
    AtomicFile f(p);
    f.stream() << "partial";
  }
  EXPECT_FALSE(fs::exists(p));
  for (const auto& e : fs::directory_iterator(p.parent_path())) {
    EXPECT_EQ(e.path().filename().string().find("never.txt.tmp"), std::string::npos);
  }
}

// A file in a folder that does not exist: the message names the file asked for and the
// missing folder, not the temporary that could not be created ("x/m.mtx.tmp-cf5bf123").
TEST(AtomicFile, AMissingFolderIsNamedWithTheFile) {
  const fs::path p = scratch("no-such-folder") / "m.mtx";
  fs::remove_all(p.parent_path());
  const std::string e = testing::input_error_of([&] { AtomicFile f(p); });
  EXPECT_NE(
      e.find(p.string() + ": cannot create output file: no folder " + p.parent_path().string()),
      std::string::npos)
      << e;
  EXPECT_EQ(e.find(".tmp-"), std::string::npos) << e;
}

TEST(Table, WritesHeaderAndRowsAndRefusesNaN) {
  Table t;
  t.add("a", Eigen::Vector2d(1.0, 0.5));
  t.add("b", Eigen::Vector2d(2.0, 1e-7));
  const fs::path p = scratch("t.csv");
  write_table(p, t);
  EXPECT_EQ(testing::read_file(p), "a,b\n1,2\n0.5,1e-07\n");

  t.columns[1](0) = std::numeric_limits<double>::quiet_NaN();
  const fs::path q = scratch("nan.csv");
  fs::remove(q);
  EXPECT_THROW(write_table(q, t), std::logic_error);
  EXPECT_FALSE(fs::exists(q));
}

TEST(Table, ListedColumnsAreAddedInOrder) {
  Table listed;
  listed.add({{"b", Eigen::Vector2d(2.0, 1e-7)}, {"a", Eigen::Vector2d(1.0, 0.5)}});
  EXPECT_EQ(listed.names, (std::vector<std::string>{"b", "a"}));
  ASSERT_EQ(listed.columns.size(), 2u);
  EXPECT_EQ(listed.columns[0], Eigen::VectorXd(Eigen::Vector2d(2.0, 1e-7)));
  EXPECT_EQ(listed.columns[1], Eigen::VectorXd(Eigen::Vector2d(1.0, 0.5)));
}

TEST(JsonWriter, NestedDocument) {
  JsonWriter w;
  w.begin_object()
      .key("name")
      .value("a\"b")
      .key("list")
      .begin_array()
      .value(1)
      .value(2.5)
      .end_array()
      .key("empty")
      .begin_object()
      .end_object()
      .end_object();
  EXPECT_EQ(
      w.str(),
      "{\n  \"name\": \"a\\\"b\",\n  \"list\": [\n    1,\n    2.5\n  ],\n  \"empty\": {}\n}\n");
  JsonWriter bad;
  EXPECT_THROW(bad.value(std::numeric_limits<double>::infinity()), std::logic_error);
}

TEST(JsonWriter, NumbersWritesTheSameAsOneKeyAndValueEach) {
  JsonWriter one_by_one;
  one_by_one.begin_object().key("b").value(0.25).key("a").value(3.0).end_object();
  JsonWriter listed;
  listed.begin_object().numbers({{"b", 0.25}, {"a", 3.0}}).end_object();
  EXPECT_EQ(listed.str(), one_by_one.str());
  EXPECT_EQ(listed.str(), "{\n  \"b\": 0.25,\n  \"a\": 3\n}\n");
}

TEST(JsonWriter, BytesThatAreNotUtf8BecomeReplacementCharacters) {
  JsonWriter w;
  // Latin-1 "acc\xb5" (a lone continuation byte), a truncated 3-byte sequence, an overlong
  // '/', a surrogate; then valid 2-, 3- and 4-byte characters, kept as they are.
  w.value(std::string_view(
      "acc\xb5|\xe2\x82|\xc0\xaf|\xed\xa0\x80|\xc2\xb5\xe2\x82\xac\xf0\x9f\x98\x80"));
  EXPECT_EQ(w.str(),
            "\"acc\\ufffd|\\ufffd\\ufffd|\\ufffd\\ufffd|\\ufffd\\ufffd\\ufffd|"
            "\xc2\xb5\xe2\x82\xac\xf0\x9f\x98\x80\"");
}

}  // namespace
}  // namespace jointlab::data

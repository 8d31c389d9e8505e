#include "jointlab/campaign/report.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::campaign {
namespace {

namespace fs = std::filesystem;

// RFC 4648 section 10 test vectors.
TEST(Report, Base64MatchesRfc4648) {
  EXPECT_EQ(base64(""), "");
  EXPECT_EQ(base64("f"), "Zg==");
  EXPECT_EQ(base64("fo"), "Zm8=");
  EXPECT_EQ(base64("foo"), "Zm9v");
  EXPECT_EQ(base64("foob"), "Zm9vYg==");
  EXPECT_EQ(base64("fooba"), "Zm9vYmE=");
  EXPECT_EQ(base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(base64(std::string("\xff\x00\x80", 3)), "/wCA");
}

TEST(Report, HtmlIsSelfContainedAndEscaped) {
  const fs::path dir = jointlab::testing::scratch_folder("jointlab_report_test");
  fs::create_directories(dir);
  const std::string png("\x89PNG\r\n\x1a\nfake", 12);
  std::ofstream(dir / "f.png", std::ios::binary) << png;
  Report r;
  r.title = "a <b> & c";
  ReportSection s;
  s.heading = "h";
  s.paragraphs = {"x < y"};
  s.tables.push_back({"t", {"a", "b|c"}, {{"1", "2"}}});
  s.figures.push_back({"cap", dir / "f.png"});
  r.sections.push_back(s);
  write_report_html(r, dir / "r.html");
  write_report_markdown(r, dir / "r.md");
  const std::string h = testing::read_file(dir / "r.html");
  EXPECT_NE(h.find("a &lt;b&gt; &amp; c"), std::string::npos);
  EXPECT_NE(h.find("data:image/png;base64," + base64(png)), std::string::npos);
  EXPECT_EQ(h.find("src=\"f.png\""), std::string::npos);
  const std::string m = testing::read_file(dir / "r.md");
  EXPECT_NE(m.find("![cap](f.png)"), std::string::npos);
  EXPECT_NE(m.find("b\\|c"), std::string::npos);
  // A row of the wrong length is refused and nothing is written.
  r.sections[0].tables[0].rows[0].push_back("3");
  EXPECT_THROW(write_report_html(r, dir / "bad.html"), InputError);
  EXPECT_FALSE(fs::exists(dir / "bad.html"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace jointlab::campaign

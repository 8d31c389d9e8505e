#include "jointlab/data/json_reader.h"

#include <string>

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/data/json_writer.h"
#include "jointlab/tests/test_util.h"

namespace jointlab::data {
namespace {

TEST(JsonReader, ReadsWhatTheWriterWrites) {
  JsonWriter w;
  w.begin_object();
  w.key("program").value("jointlab process");
  w.key("files").begin_array();
  w.begin_object();
  w.key("band").value(2);
  w.key("low_hz").value(12.5);
  w.key("x").value(-1.25e-7);
  w.key("ok").value(true);
  w.key("file").null();
  w.key("name").value("a \"q\" \\ \n\t");
  w.end_object();
  w.end_array();
  w.end_object();
  const JsonValue v = parse_json(w.str(), "w.json");
  ASSERT_TRUE(v.is_object());
  EXPECT_EQ(v.find("program")->string(), "jointlab process");
  const JsonValue& f = v.find("files")->items().at(0);
  EXPECT_EQ(f.find("band")->number(), 2);
  EXPECT_EQ(f.find("low_hz")->number(), 12.5);
  EXPECT_EQ(f.find("x")->number(), -1.25e-7);
  EXPECT_TRUE(f.find("ok")->boolean());
  EXPECT_TRUE(f.find("file")->is_null());
  EXPECT_EQ(f.find("name")->string(), "a \"q\" \\ \n\t");
  EXPECT_EQ(f.find("missing"), nullptr);
  EXPECT_EQ(f.members().front().first, "band");  // file order kept
}

TEST(JsonReader, Escapes) {
  const JsonValue v = parse_json(R"(["\u00e9\ud83d\ude00\/", [], {}, 0, -0.5E+2])", "e.json");
  ASSERT_EQ(v.items().size(), 5u);
  EXPECT_EQ(v.items()[0].string(), "\xc3\xa9\xf0\x9f\x98\x80/");
  EXPECT_TRUE(v.items()[1].is_array());
  EXPECT_TRUE(v.items()[2].is_object());
  EXPECT_EQ(v.items()[4].number(), -50);
}

TEST(JsonReader, DefectsGiveOneLineNamingFileLineAndByte) {
  struct Case {
    const char* text;
    const char* says;
  };
  const Case cases[] = {
      {"{\"a\": 1,\n \"b\": }", "s.json:2: column 7 (byte 15)"},
      {"{\"a\": 1} x", "after the JSON document"},
      {"{\"a\": 01}", "leading zeros"},
      {"{\"a\": +1}", "does not start a JSON value"},
      {"{\"a\": NaN}", "does not start a JSON value"},
      {"{\"a\": 1e999}", "out of range"},
      {"{\"a\": \"x", "end of file inside a string"},
      {"{\"a\": \"\\q\"}", "unknown escape"},
      {"{\"a\": 1, \"a\": 2}", "duplicate key \"a\""},
      {"[1, 2", "end of file"},
      {"{a: 1}", "key must be a string"},
      {"", "end of file"},
      {"[\"\\ud800\"]", "surrogate"},
      {"tru", "does not start"},
  };
  for (const Case& c : cases) {
    const std::string m = testing::input_error_of([&] { parse_json(c.text, "s.json"); });
    EXPECT_NE(m.find(c.says), std::string::npos) << c.text << " -> " << m;
    EXPECT_EQ(m.rfind("s.json:", 0), 0u) << m;
  }
  const std::string deep(300, '[');
  EXPECT_NE(testing::input_error_of([&] { parse_json(deep, "d.json"); }).find("deeper"),
            std::string::npos);
  EXPECT_NE(testing::input_error_of([] {
              read_json("/nonexistent/summary.json");
            }).find("/nonexistent/summary.json: cannot open"),
            std::string::npos);
}

}  // namespace
}  // namespace jointlab::data

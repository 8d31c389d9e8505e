#include "jointlab/correlate/sensors.h"

#include <gtest/gtest.h>

#include "jointlab/core/error.h"
#include "jointlab/correlate/two_chain.h"

namespace jointlab::correlate {
namespace {

// A sensors text read at the edge (data::parse_sensors_file) and resolved against `model`.
std::vector<Sensor> parse_sensors(const std::string& text, const std::string& name,
                                  const model::Model& model) {
  return sensors_of(data::parse_sensors_file(text, name), model);
}

TEST(Sensors, ParsesIndicesLabelsAndSigns) {
  model::Model m = two_chain_structure();
  m.dof_labels.clear();
  for (int i = 0; i < m.size(); ++i) m.dof_labels.push_back(std::to_string(1000 + i) + ":3");
  const auto s = parse_sensors(
      "# a comment\nchannel,dof,sign\nacc1,1002:3,-1\nacc2, 5 ,\nacc3,7,1\n", "sensors.csv", m);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].dof, 2);
  EXPECT_EQ(s[0].sign, -1.0);
  EXPECT_EQ(s[1].dof, 5);
  EXPECT_EQ(s[1].sign, 1.0);
  EXPECT_EQ(find_sensor(s, "acc3"), 2);
  EXPECT_EQ(find_sensor(s, "nope"), -1);
  Eigen::MatrixXd shapes = Eigen::MatrixXd::Random(m.size(), 2);
  const Eigen::MatrixXd at = shapes_at_sensors(s, shapes);
  EXPECT_EQ(at(0, 1), -shapes(2, 1));
  EXPECT_EQ(at(2, 0), shapes(7, 0));
  // A spreadsheet's trailing comma on the header and the rows; a quoted channel name.
  const auto t = parse_sensors("channel,dof,\n\"acc, tip\",3,\n", "sensors.csv", m);
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].channel, "acc, tip");
  EXPECT_EQ(t[0].dof, 3);
}

// The message parse_sensors refuses `text` (as s.csv) with, or "no error".
std::string sensors_error(const std::string& text, const model::Model& m) {
  try {
    parse_sensors(text, "s.csv", m);
  } catch (const InputError& e) {
    return std::string(e.what());
  }
  return std::string("no error");
}

TEST(Sensors, BadInputNamesFileAndLine) {
  const model::Model m = two_chain_structure();
  const auto message = [&](const std::string& text) { return sensors_error(text, m); };
  EXPECT_NE(message("chan,dof\na,1\n").find("s.csv:1"), std::string::npos);
  EXPECT_NE(message("channel,dof\na,99\n").find("s.csv:2"), std::string::npos);
  EXPECT_NE(message("channel,dof\na,1\na,2\n").find("twice"), std::string::npos);
  EXPECT_NE(message("channel,dof,sign\na,1,2\n").find("sign"), std::string::npos);
  // The two-chain model has no labels: a label says what it needs, not that a node is absent.
  EXPECT_NE(message("channel,dof\na,1:3\n")
                .find("s.csv:2: dof '1:3': a \"node:component\" label needs the model's "
                      "matrices.dof_labels"),
            std::string::npos)
      << message("channel,dof\na,1:3\n");
}

// A label the model lacks names what its node has: the likely slip is the component.
TEST(Sensors, AMissingLabelNamesTheNodesLabels) {
  model::Model m = two_chain_structure();
  m.dof_labels.clear();
  for (int i = 0; i < m.size(); ++i) m.dof_labels.push_back(std::to_string(1000 + i) + ":3");
  const auto message = [&](const std::string& text) { return sensors_error(text, m); };
  EXPECT_NE(message("channel,dof\na,1002:1\n")
                .find("s.csv:2: dof '1002:1' is not a label of the "
                      "model's dof_labels: node 1002 has only 1002:3"),
            std::string::npos)
      << message("channel,dof\na,1002:1\n");
  EXPECT_NE(message("channel,dof\na,9:3\n").find("it has no node 9"), std::string::npos);
}

}  // namespace
}  // namespace jointlab::correlate

namespace jointlab::correlate {
namespace {

// A DOF written as other tools write it names the label (and sign) to give, in one line:
// before, '9001:+3', '9001:3+', '9001:z-', '9001: 3', '9001:3.0' and 'Tz' got only "node 9001
// has only 9001:3", '9001 :3' "it has no node 9001 "; a header 'Channel,DOF' or one separated
// by ';' or tabs (as the modes table may be) was refused without saying what it found, and a
// sign '-1.0' or '-' was refused without the fix.
TEST(Sensors, ADofWrittenAsOtherToolsWriteItSaysWhatToGive) {
  model::Model m = two_chain_structure();
  m.dof_labels.clear();
  for (int i = 0; i < m.size(); ++i) m.dof_labels.push_back(std::to_string(9000 + i) + ":3");
  const auto message = [&](const std::string& dof) {
    return sensors_error("channel,dof\na," + dof + "\n", m);
  };
  const std::string named =
      "(a component is a number, 1-6 for x, y, z, rx, ry, rz, and a channel "
      "that reads against it has sign -1: give 9001:3";
  const std::string signed_number =
      "(a component is a number 1-6 without a sign, and a channel that reads against it has sign "
      "-1: give 9001:3";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"9001:+3", signed_number + ")"},
      {"9001:3+", signed_number + ")"},
      {"9001:-3", signed_number + " and sign -1)"},
      {"9001:3-", signed_number + " and sign -1)"},
      {"9001:z", named + ")"},
      {"9001:Z", named + ")"},
      {"9001:+z", named + ")"},
      {"9001:+Z", named + ")"},
      {"9001:z+", named + ")"},
      {"9001:-Z", named + " and sign -1)"},
      {"9001:z-", named + " and sign -1)"},
      {"9001:Tz", named + ")"},
      {"9001: 3", "(a label has no blanks: give 9001:3)"},
      {"9001 : -z", "(a label has no blanks, " + named.substr(1) + " and sign -1)"},
      {"9001:3.0", "(a component is a whole number 1-6 as written in dof_labels: give 9001:3)"},
  };
  for (const auto& [dof, hint] : cases) {
    const std::string e = message(dof);
    EXPECT_EQ(e.find("s.csv:2: dof '" + dof +
                     "' is not a label of the model's dof_labels: node "
                     "9001 has only 9001:3 " +
                     hint),
              0u)
        << dof << ": " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  }
  // Not a slip of the form: no hint.
  EXPECT_EQ(message("9001:1").find(" ("), std::string::npos) << message("9001:1");
  EXPECT_EQ(message("9001:7").find(" ("), std::string::npos) << message("9001:7");

  // Headers in any case, separated by ';' or tabs, and signs written as numbers, are read.
  for (const std::string& text : {std::string("Channel,DOF,Sign\na,9001:3,-1.0\n"),
                                  std::string("channel;dof;sign\na;9001:3;-1\n"),
                                  std::string("channel\tdof\tsign\na\t9001:3\t-1\n")}) {
    const std::vector<Sensor> s = parse_sensors(text, "s.csv", m);
    ASSERT_EQ(s.size(), 1u) << text;
    EXPECT_EQ(s[0].dof, 1) << text;
    EXPECT_EQ(s[0].sign, -1.0) << text;
  }
  EXPECT_EQ(sensors_error("chan,dof\na,1\n", m),
            "s.csv:1: expected the header 'channel,dof[,sign]' (',', ';' or tab between the "
            "cells), found 'chan,dof'");
  EXPECT_EQ(sensors_error("channel,dof,sign\na,9001:3,-\n", m),
            "s.csv:2: sign '-' must be 1 or -1: give -1");
}

}  // namespace
}  // namespace jointlab::correlate

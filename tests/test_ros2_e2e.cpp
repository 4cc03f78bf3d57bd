// `voca run --ros2` end to end: a ROS 2 subscriber made of the same generated types, on Cyclone DDS
// over loopback without multicast (as CI's sandbox allows), receives the odometry and /tf of a real
// run and every message must be the trajectory file's row of its frame, to the digits the file has;
// bad ROS_DOMAIN_ID values and topic names are named before any input is read.

#include <doctest/doctest.h>
#include <stdlib.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/test_ros2_support.h"
#include "tests/test_support.h"

using namespace voca;
namespace fs = std::filesystem;

namespace {

// A TUM row as text and as the values it reads back to (the writer prints each double's shortest
// round-trip form, so reading gives back exactly the double that was written).
struct TumRow {
  std::string stamp;  // "sec.nanoseconds", 9 decimals
  std::int64_t t_ns = 0;
  double values[7] = {};  // tx ty tz qx qy qz qw
};

std::vector<TumRow> readTum(const fs::path& path) {
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "cannot read " << path);
  std::vector<TumRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    TumRow row;
    fields >> row.stamp;
    const std::size_t dot = row.stamp.find('.');
    REQUIRE_MESSAGE((dot != std::string::npos && row.stamp.size() - dot == 10), "stamp " << row.stamp);
    row.t_ns = std::stoll(row.stamp.substr(0, dot)) * 1'000'000'000 + std::stoll(row.stamp.substr(dot + 1));
    for (double& value : row.values) {
      std::string text;
      fields >> text;
      value = std::strtod(text.c_str(), nullptr);
    }
    REQUIRE_MESSAGE(!fields.fail(), "row " << line);
    rows.push_back(row);
  }
  return rows;
}

// t_ns -> "tracking", "reset" or "lost", from the statistics JSON's frame rows.
std::map<std::int64_t, std::string> trackingStates(const fs::path& statistics) {
  std::ifstream in(statistics);
  const nlohmann::json j = nlohmann::json::parse(in);
  const std::vector<std::string> columns = j.at("frame_columns").get<std::vector<std::string>>();
  std::size_t t_column = 0, state_column = 0;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (columns[c] == "t_ns") t_column = c;
    if (columns[c] == "state") state_column = c;
  }
  std::map<std::int64_t, std::string> states;
  for (const nlohmann::json& row : j.at("frame_rows")) {
    states[row.at(t_column).get<std::int64_t>()] = row.at(state_column).get<std::string>();
  }
  return states;
}

std::string stampText(std::int32_t sec, std::uint32_t nanosec) {
  char text[32];
  std::snprintf(text, sizeof text, "%d.%09u", sec, nanosec);
  return text;
}

// Runs `voca run <input> --ros2` with a subscriber listening and checks every message against the
// trajectory file. Returns the number of odometry messages received.
std::size_t expectPublishedTrajectory(const fs::path& input, const std::string& name) {
  INFO(name);
  const std::uint32_t domain = test::useLoopbackDomain();
  const std::string topic = test::uniqueTopicName("odom");
  test::RosSubscriber subscriber(domain);
  const dds_entity_t odometry_reader = subscriber.reader(nav_msgs_msg_dds__Odometry__desc, "rt" + topic);
  const dds_entity_t tf_reader = subscriber.reader(tf2_msgs_msg_dds__TFMessage__desc, "rt/tf");
  test::ScratchDir dir("ros2-e2e");
  const test::CommandOutput run =
      test::runVocaOutput("run " + input.string() + " -o " + (dir / "traj.txt").string() + " --stats " +
                          (dir / "stats.json").string() + " --ros2 --ros2-topic " + topic);
  INFO(run.text);
  REQUIRE(run.exit_code == 0);

  const std::vector<TumRow> rows = readTum(dir / "traj.txt");
  const std::map<std::int64_t, std::string> states = trackingStates(dir / "stats.json");
  REQUIRE(states.size() == rows.size());
  std::vector<const TumRow*> tracked;
  for (const TumRow& row : rows) {
    if (states.at(row.t_ns) == "tracking") tracked.push_back(&row);
  }
  REQUIRE(!tracked.empty());

  const std::vector<test::ReceivedOdometry> odometry =
      test::RosSubscriber::take<test::ReceivedOdometry, nav_msgs_msg_dds__Odometry_>(odometry_reader,
                                                                                     test::copyOdometry);
  std::vector<test::ReceivedTransform> transforms;
  for (const std::vector<test::ReceivedTransform>& message :
       test::RosSubscriber::take<std::vector<test::ReceivedTransform>, tf2_msgs_msg_dds__TFMessage_>(
           tf_reader, test::copyTransforms)) {
    CHECK(message.size() == 1);
    transforms.insert(transforms.end(), message.begin(), message.end());
  }
  // Every tracked frame, in order: the run waits for reliable acknowledgment before it ends, and
  // discovery on loopback matches the waiting subscriber long before the first pose (10-30 ms after
  // the publisher joined, against 110-270 ms to the first pose, measured on a loaded 2-core machine).
  // The summary counts the same.
  CHECK(odometry.size() == tracked.size());
  CHECK(transforms.size() == tracked.size());
  CHECK(run.text.find("ros2: " + std::to_string(tracked.size()) + " odometry messages on rt" + topic) !=
        std::string::npos);
  for (std::size_t i = 0; i < std::min(odometry.size(), tracked.size()); ++i) {
    const TumRow& row = *tracked[i];
    const test::ReceivedOdometry& m = odometry[i];
    INFO("row " << row.stamp);
    CHECK(stampText(m.sec, m.nanosec) == row.stamp);
    CHECK(m.frame_id == "odom");
    CHECK(m.child_frame_id == "base_link");
    for (int k = 0; k < 3; ++k) CHECK(m.position[k] == row.values[k]);
    for (int k = 0; k < 4; ++k) CHECK(m.orientation[k] == row.values[3 + k]);
    for (double c : m.pose_covariance) CHECK(c == 0.0);
    if (i < transforms.size()) {
      const test::ReceivedTransform& t = transforms[i];
      CHECK(stampText(t.sec, t.nanosec) == row.stamp);
      CHECK(t.frame_id == "odom");
      CHECK(t.child_frame_id == "base_link");
      for (int k = 0; k < 3; ++k) CHECK(t.translation[k] == row.values[k]);
      for (int k = 0; k < 4; ++k) CHECK(t.rotation[k] == row.values[3 + k]);
    }
  }
  // The first pose has no velocity estimate; the others move as the poses do: |v| dt is the distance
  // between consecutive positions to first order (the chord of the arc the twist describes).
  REQUIRE(!odometry.empty());
  CHECK(odometry[0].twist_covariance[0] == -1.0);
  for (std::size_t i = 1; i < std::min(odometry.size(), tracked.size()); ++i) {
    const test::ReceivedOdometry& m = odometry[i];
    CHECK(m.twist_covariance[0] == 0.0);
    const double dt_s = static_cast<double>(tracked[i]->t_ns - tracked[i - 1]->t_ns) * 1e-9;
    const auto norm = [](double x, double y, double z) { return std::sqrt(x * x + y * y + z * z); };
    const double step_m =
        norm(tracked[i]->values[0] - tracked[i - 1]->values[0], tracked[i]->values[1] - tracked[i - 1]->values[1],
             tracked[i]->values[2] - tracked[i - 1]->values[2]);
    const double speed = norm(m.linear[0], m.linear[1], m.linear[2]);
    // The arc is at most a few percent longer than its chord at these turn rates per frame.
    CHECK(speed * dt_s == doctest::Approx(step_m).epsilon(0.05).scale(1e-3));
  }
  return odometry.size();
}

}  // namespace

TEST_CASE("voca run --ros2 on a rendered sequence: every message is its frame's trajectory row") {
  test::ScratchDir dir("ros2-e2e-synth");
  REQUIRE(test::renderSynth(dir / "synth", "--seconds 2 --supersample 1") == 0);
  REQUIRE(test::runVoca("encode " + (dir / "synth").string() + " --out " + (dir / "video").string() +
                        " --bitrate 500k") == 0);
  CHECK(expectPublishedTrajectory(dir / "video", "rendered, 500 kbit/s") > 30);
}

TEST_CASE("voca run --ros2 on KITTI 06 (51 real frames)") {
  const auto data = test::sharedData("kitti06_first51/sequences/06");
  if (!data) return;
  CHECK(expectPublishedTrajectory(*data, "KITTI 06") > 40);
}

TEST_CASE("bad ROS_DOMAIN_ID values and ROS names are named before the input is read") {
  test::useLoopbackDomain();
  const std::string saved = std::getenv("ROS_DOMAIN_ID");
  const std::string run = "run /nonexistent/dataset -o /nonexistent/traj.txt --ros2";
  for (const char* bad : {"abc", "233", "-1"}) {
    setenv("ROS_DOMAIN_ID", bad, 1);
    const test::CommandOutput out = test::runVocaOutput(run);
    INFO(out.text);
    CHECK(out.exit_code == 1);
    test::expectError(out.text, std::string("voca run: error: ROS_DOMAIN_ID=\"") + bad +
                                    "\": expected a ROS 2 domain id, an integer from 0 to 232");
  }
  setenv("ROS_DOMAIN_ID", saved.c_str(), 1);

  const test::CommandOutput topic = test::runVocaOutput(run + " --ros2-topic 2d/odom");
  CHECK(topic.exit_code == 1);
  test::expectError(topic.text,
                    "voca run: error: --ros2-topic \"2d/odom\": a part of a ROS topic name must not start "
                    "with a digit (character 1)");
  const test::CommandOutput frame = test::runVocaOutput(run + " --ros2-base-frame /base_link");
  CHECK(frame.exit_code == 1);
  test::expectError(frame.text, "--ros2-base-frame \"/base_link\": tf2 frame ids do not start with '/'");
  const test::CommandOutput without = test::runVocaOutput("run /nonexistent -o x.txt --ros2-topic /odom");
  CHECK(without.exit_code == 2);
  test::expectError(without.text, "--ros2-topic requires --ros2");
  const test::CommandOutput live = test::runVocaOutput("live --camera /dev/null --calib x.json --track-only --ros2");
  CHECK(live.exit_code == 1);
  test::expectError(live.text, "--ros2 publishes poses; --track-only estimates none");
}

TEST_CASE("voca run --help and voca live --help say what --ros2 publishes, its QoS and ROS_DOMAIN_ID") {
  for (const char* command : {"run", "live"}) {
    const test::CommandOutput help = test::runVocaOutput(std::string(command) + " --help");
    INFO(help.text);
    CHECK(help.exit_code == 0);
    for (const char* part :
         {"--ros2-topic", "nav_msgs/msg/Odometry", "rt/odom", "tf2_msgs/msg/TFMessage",
          "reliable, volatile, keep-last 10 (/odom) and 100 (/tf)", "ROS_DOMAIN_ID", "CYCLONEDDS_URI"}) {
      CHECK(help.text.find(part) != std::string::npos);
    }
  }
}

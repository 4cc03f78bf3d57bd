// ROS 2 over DDS without ROS (drivers/ros2, pipeline/sinks/ros2_sink): ROS's name and domain rules,
// the twist from two poses, the bytes Cyclone puts on the wire for our IDL against the layout the
// IDL implies (so a wrong type definition cannot pass unnoticed), and the sink's policy (tracked
// frames only), ring (drops counted, nothing allocated on the write thread) and drain at the end
// (test_ros2_sink.cpp).

#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "drivers/ros2/odometry_publisher.h"
#include "drivers/ros2/ros2_names.h"
#include "tests/test_ros2_support.h"
#include "tests/test_support.h"

using namespace voca;
using voca::test::twistOf;
using voca::test::Vec6;

namespace {

// Little-endian reads at a byte offset of a CDR buffer.
template <typename T>
T readAt(const std::vector<unsigned char>& bytes, std::size_t offset) {
  REQUIRE(offset + sizeof(T) <= bytes.size());
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}
std::string stringAt(const std::vector<unsigned char>& bytes, std::size_t offset, std::size_t length) {
  REQUIRE(offset + length <= bytes.size());
  return {reinterpret_cast<const char*>(bytes.data()) + offset, length};
}

ros2::OdometryPublisherOptions options(const std::string& topic) {
  ros2::OdometryPublisherOptions o;
  o.domain_id = test::useLoopbackDomain();
  o.topic = topic;
  return o;
}

}  // namespace

TEST_CASE("topic names resolve in the root namespace; names ROS rejects are named with the reason") {
  CHECK(ros2::fullyQualifiedTopicName("odom", "--ros2-topic") == "/odom");
  CHECK(ros2::fullyQualifiedTopicName("/odom", "--ros2-topic") == "/odom");
  CHECK(ros2::fullyQualifiedTopicName("robot_1/vo/odom", "--ros2-topic") == "/robot_1/vo/odom");
  CHECK(ros2::ddsTopicName("/robot_1/odom") == "rt/robot_1/odom");
  const auto error = [](const std::string& name) {
    return test::inputErrorOf([&] { ros2::fullyQualifiedTopicName(name, "--ros2-topic"); });
  };
  test::expectError(error(""), "--ros2-topic: an empty topic name");
  test::expectError(error("/"), "the root alone names no topic name");
  test::expectError(error("odom/"), "must not end with '/'");
  test::expectError(error("/a//odom"), "an empty part");
  test::expectError(error("/robot/2d_odom"), "must not start with a digit (character 8)");
  test::expectError(error("9odom"), "must not start with a digit (character 1)");
  test::expectError(error("odom-1"), "character 5 ('-') is not allowed");
  test::expectError(error("/vo odom"), "character 4 (' ') is not allowed");
  test::expectError(error("~/odom"), "private topic");
  test::expectError(error("/{node}/odom"), "substitutions");
  CHECK(ros2::fullyQualifiedTopicName(std::string(246, 'a'), "--ros2-topic").size() == 247);
  test::expectError(error(std::string(247, 'a')), "has 248 characters; ROS 2 allows 247");
}

TEST_CASE("frame ids: tf2's rules") {
  CHECK_NOTHROW(ros2::checkFrameId("odom", "--ros2-odom-frame"));
  CHECK_NOTHROW(ros2::checkFrameId("robot1/base_link", "--ros2-base-frame"));
  test::expectError(test::inputErrorOf([] { ros2::checkFrameId("", "--ros2-odom-frame"); }),
                    "--ros2-odom-frame: an empty frame id");
  test::expectError(test::inputErrorOf([] { ros2::checkFrameId("/odom", "--ros2-odom-frame"); }),
                    "do not start with '/' (write \"odom\")");
  test::expectError(test::inputErrorOf([] { ros2::checkFrameId("base link", "--ros2-base-frame"); }),
                    "character 5 (' ') is not allowed");
}

TEST_CASE("ROS_DOMAIN_ID: unset or empty is 0, else an integer 0..232") {
  CHECK(ros2::parseDomainId(nullptr) == 0);
  CHECK(ros2::parseDomainId("") == 0);
  CHECK(ros2::parseDomainId("0") == 0);
  CHECK(ros2::parseDomainId("42") == 42);
  CHECK(ros2::parseDomainId("232") == 232);
  for (const char* bad : {"233", "-1", "abc", " 1", "1 ", "1e2", "0x10", "4294967296", "+5"}) {
    INFO("ROS_DOMAIN_ID=" << bad);
    test::expectError(
        test::inputErrorOf([&] { ros2::parseDomainId(bad); }),
        std::string("ROS_DOMAIN_ID=\"") + bad + "\": expected a ROS 2 domain id, an integer from 0 to 232");
  }
}

TEST_CASE("bodyTwist: the constant body velocity between two poses") {
  const SE3d T_world_prev(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized())),
                          Eigen::Vector3d(4.0, -1.0, 2.5));
  const double dt_s = 0.05;
  const Vec6 xi = twistOf(2.0, -0.3, 0.1, 0.2, -0.4, 1.5);
  const SE3d T_world_cur = T_world_prev * SE3d::exp(xi * dt_s);
  // log(exp(x)) is exact to rounding; the 1e-9 allows for the division by dt.
  CHECK((ros2::bodyTwist(T_world_prev, T_world_cur, dt_s) - xi).norm() < 1e-9);

  // A car on a circle (yaw rate 0.5 rad/s at 10 m/s, x forward): all speed is forward in the body
  // frame, none sideways, however long the step.
  const SE3d start;
  const double yaw = 0.5 * 0.2;  // 0.2 s
  const double radius = 10.0 / 0.5;
  const SE3d end(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())),
                 Eigen::Vector3d(radius * std::sin(yaw), radius * (1.0 - std::cos(yaw)), 0.0));
  CHECK((ros2::bodyTwist(start, end, 0.2) - twistOf(10.0, 0.0, 0.0, 0.0, 0.0, 0.5)).norm() < 1e-9);
}

TEST_CASE("Odometry and TFMessage on the wire: XCDR1 little-endian at the offsets the IDL implies") {
  const std::string topic = test::uniqueTopicName("odom");
  test::RosSubscriber subscriber(test::useLoopbackDomain());
  const dds_entity_t odometry_reader = subscriber.reader(nav_msgs_msg_dds__Odometry__desc, "rt" + topic);
  const dds_entity_t tf_reader = subscriber.reader(tf2_msgs_msg_dds__TFMessage__desc, "rt/tf");
  ros2::OdometryPublisher publisher(options(topic));
  CHECK(publisher.odometryDdsTopic() == "rt" + topic);
  REQUIRE(test::RosSubscriber::waitForWriters(odometry_reader, 1, std::chrono::seconds(10)));
  REQUIRE(test::RosSubscriber::waitForWriters(tf_reader, 1, std::chrono::seconds(10)));

  ros2::OdometrySample sample;
  sample.t_ns = 1'234'567'890'987'654'321;
  sample.T_odom_base = SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())),
                            Eigen::Vector3d(1.5, -2.25, 3.125));
  sample.linear_velocity_mps = Eigen::Vector3d(0.25, -0.5, 1.0);
  sample.angular_velocity_radps = Eigen::Vector3d(0.125, 0.0625, -2.0);
  sample.twist_known = true;
  REQUIRE(publisher.publish(sample));
  sample.twist_known = false;
  sample.t_ns = -500'000'000;  // before the epoch: ROS's Time rounds the seconds down
  REQUIRE(publisher.publish(sample));
  CHECK(publisher.waitForAcknowledgments(std::chrono::seconds(5)));
  const Eigen::Quaterniond& q = sample.T_odom_base.unitQuaternion();

  // Odometry, "odom" and "base_link" as the frames. Offsets count from the CDR data after the 4-byte
  // encapsulation header; XCDR1 aligns 8-byte types to 8 (XCDR2 would to 4, moving every double).
  const std::vector<unsigned char> odometry = test::RosSubscriber::takeSerialized(odometry_reader);
  REQUIRE(odometry.size() == 4 + 720);
  CHECK(std::vector<unsigned char>(odometry.begin(), odometry.begin() + 4) == std::vector<unsigned char>{0, 1, 0, 0});
  const auto at = [](std::size_t data_offset) { return 4 + data_offset; };
  CHECK(readAt<std::int32_t>(odometry, at(0)) == 1'234'567'890);  // header.stamp.sec
  CHECK(readAt<std::uint32_t>(odometry, at(4)) == 987'654'321);   // header.stamp.nanosec
  CHECK(readAt<std::uint32_t>(odometry, at(8)) == 5);             // header.frame_id length with its NUL
  CHECK(stringAt(odometry, at(12), 5) == std::string("odom\0", 5));
  CHECK(readAt<std::uint32_t>(odometry, at(20)) == 10);  // child_frame_id, aligned to 4
  CHECK(stringAt(odometry, at(24), 10) == std::string("base_link\0", 10));
  // pose.pose.position.x = 1.5 is 0x3FF8000000000000, at 40 (34 rounded up to 8), low byte first.
  CHECK(std::vector<unsigned char>(odometry.begin() + at(40), odometry.begin() + at(48)) ==
        std::vector<unsigned char>{0, 0, 0, 0, 0, 0, 0xF8, 0x3F});
  CHECK(readAt<double>(odometry, at(48)) == -2.25);
  CHECK(readAt<double>(odometry, at(56)) == 3.125);
  CHECK(readAt<double>(odometry, at(64)) == q.x());  // orientation in ROS's order: x y z w
  CHECK(readAt<double>(odometry, at(72)) == q.y());
  CHECK(readAt<double>(odometry, at(80)) == q.z());
  CHECK(readAt<double>(odometry, at(88)) == q.w());
  for (int i = 0; i < 36; ++i) CHECK(readAt<double>(odometry, at(96 + 8 * i)) == 0.0);  // pose covariance: unknown
  CHECK(readAt<double>(odometry, at(384)) == 0.25);                                     // twist.twist.linear
  CHECK(readAt<double>(odometry, at(392)) == -0.5);
  CHECK(readAt<double>(odometry, at(400)) == 1.0);
  CHECK(readAt<double>(odometry, at(408)) == 0.125);  // twist.twist.angular
  CHECK(readAt<double>(odometry, at(416)) == 0.0625);
  CHECK(readAt<double>(odometry, at(424)) == -2.0);
  for (int i = 0; i < 36; ++i) CHECK(readAt<double>(odometry, at(432 + 8 * i)) == 0.0);  // twist covariance

  const std::vector<unsigned char> second = test::RosSubscriber::takeSerialized(odometry_reader);
  REQUIRE(second.size() == 4 + 720);
  CHECK(readAt<std::int32_t>(second, at(0)) == -1);
  CHECK(readAt<std::uint32_t>(second, at(4)) == 500'000'000);
  CHECK(readAt<double>(second, at(432)) == -1.0);  // no velocity estimate: ROS's -1 in element 0
  for (int i = 1; i < 36; ++i) CHECK(readAt<double>(second, at(432 + 8 * i)) == 0.0);

  // TFMessage: a sequence of one TransformStamped.
  const std::vector<unsigned char> tf = test::RosSubscriber::takeSerialized(tf_reader);
  REQUIRE(tf.size() == 4 + 96);
  CHECK(std::vector<unsigned char>(tf.begin(), tf.begin() + 4) == std::vector<unsigned char>{0, 1, 0, 0});
  CHECK(readAt<std::uint32_t>(tf, at(0)) == 1);  // transforms: length
  CHECK(readAt<std::int32_t>(tf, at(4)) == 1'234'567'890);
  CHECK(readAt<std::uint32_t>(tf, at(8)) == 987'654'321);
  CHECK(readAt<std::uint32_t>(tf, at(12)) == 5);
  CHECK(stringAt(tf, at(16), 5) == std::string("odom\0", 5));
  CHECK(readAt<std::uint32_t>(tf, at(24)) == 10);
  CHECK(stringAt(tf, at(28), 10) == std::string("base_link\0", 10));
  CHECK(readAt<double>(tf, at(40)) == 1.5);  // transform.translation, at 38 rounded up to 8
  CHECK(readAt<double>(tf, at(48)) == -2.25);
  CHECK(readAt<double>(tf, at(56)) == 3.125);
  CHECK(readAt<double>(tf, at(64)) == q.x());  // transform.rotation
  CHECK(readAt<double>(tf, at(72)) == q.y());
  CHECK(readAt<double>(tf, at(80)) == q.z());
  CHECK(readAt<double>(tf, at(88)) == q.w());
}

TEST_CASE("a stamp that does not fit ROS's Time is refused and named; bad options are input errors") {
  ros2::OdometryPublisher publisher(options(test::uniqueTopicName("odom")));
  ros2::OdometrySample sample;
  sample.t_ns = std::int64_t{1} << 62;
  CHECK_FALSE(publisher.publish(sample));
  test::expectError(publisher.lastError(), "does not fit ROS's Time");

  ros2::OdometryPublisherOptions bad = options("/odom");
  bad.domain_id = 233;
  test::expectError(test::inputErrorOf([&] { ros2::OdometryPublisher p(bad); }), "ROS 2 domain 233: expected 0 to 232");
  bad = options("odom-1");
  test::expectError(test::inputErrorOf([&] { ros2::OdometryPublisher p(bad); }), "is not allowed in a ROS topic name");
  bad = options("/odom");
  bad.base_frame = "/base_link";
  test::expectError(test::inputErrorOf([&] { ros2::OdometryPublisher p(bad); }), "do not start with '/'");
}

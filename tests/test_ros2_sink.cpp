// The ROS 2 sink (pipeline/sinks/ros2_sink.h): tracked frames only, twists from the previous tracked
// or reset pose, a ring that drops and counts when full, nothing allocated on the write thread, and
// everything left in the ring published at the end. Its own source file because it replaces operator
// new/delete (test_alloc_counter.h) for the executable, and GCC then sees through the inlined
// operators of neighbouring code and warns falsely.

#include <doctest/doctest.h>

#include <vector>

#include "pipeline/sinks/ros2_sink.h"
#include "tests/test_alloc_counter.h"
#include "tests/test_ros2_support.h"
#include "tests/test_support.h"

using namespace voca;
using voca::test::twistOf;
using voca::test::Vec6;

namespace {

ros2::OdometryPublisherOptions options(const std::string& topic) {
  ros2::OdometryPublisherOptions o;
  o.domain_id = test::useLoopbackDomain();
  o.topic = topic;
  return o;
}

pipeline::FrameSlot slotAt(std::int64_t t_ns, const SE3d& T_world_body, TrackingState state) {
  pipeline::FrameSlot slot;
  slot.pose.t_ns = t_ns;
  slot.pose.T_world_body = T_world_body;
  slot.pose.state = state;
  return slot;
}

}  // namespace

TEST_CASE("the sink publishes tracked frames only, with the twist from the previous tracked or reset pose") {
  const std::string topic = test::uniqueTopicName("odom");
  test::RosSubscriber subscriber(test::useLoopbackDomain());
  const dds_entity_t reader = subscriber.reader(nav_msgs_msg_dds__Odometry__desc, "rt" + topic);
  ros2::OdometryPublisherOptions o = options(topic);
  o.odom_frame = "robot1/odom";
  o.base_frame = "robot1/base_link";
  pipeline::Ros2Sink sink(o);
  REQUIRE(test::RosSubscriber::waitForWriters(reader, 1, std::chrono::seconds(10)));
  sink.start();

  const std::int64_t step_ns = 50'000'000;
  const Vec6 before = twistOf(1.0, 0.0, 0.0, 0.0, 0.0, 0.2);
  const Vec6 after = twistOf(0.5, 0.1, 0.0, 0.0, 0.3, 0.0);
  const SE3d T0;
  const SE3d T1 = T0 * SE3d::exp(before * 0.05);
  const SE3d T4 = T1 * SE3d::exp(after * 0.05);  // tracking restarted at T1 (the reset frame, 3)
  const SE3d T7(Eigen::Quaterniond::Identity(), Eigen::Vector3d(9.0, 0.0, 0.0));
  sink.consume(slotAt(0, T0, TrackingState::kTracking));            // first pose: no twist
  sink.consume(slotAt(step_ns, T1, TrackingState::kTracking));      // twist `before`
  sink.consume(slotAt(2 * step_ns, T1, TrackingState::kLost));      // held: not published
  sink.consume(slotAt(3 * step_ns, T1, TrackingState::kReset));     // held, anchors the new track
  sink.consume(slotAt(4 * step_ns, T4, TrackingState::kTracking));  // twist `after`, from the anchor
  sink.consume(slotAt(5 * step_ns, T4, TrackingState::kLost));
  sink.consume(slotAt(6 * step_ns, T4, TrackingState::kLost));
  sink.consume(slotAt(7 * step_ns, T7, TrackingState::kTracking));  // after lost frames: no twist
  sink.finish();
  const pipeline::Ros2Sink::Counters counters = sink.counters();
  CHECK(counters.published == 4);
  CHECK(counters.untracked == 4);
  CHECK(counters.dropped == 0);
  CHECK(counters.failed == 0);
  test::expectError(sink.summary(), "ros2: 4 odometry messages on rt" + topic);
  test::expectError(sink.summary(), "4 lost or reset frames not published");

  const std::vector<test::ReceivedOdometry> received =
      test::RosSubscriber::take<test::ReceivedOdometry, nav_msgs_msg_dds__Odometry_>(reader, test::copyOdometry);
  REQUIRE(received.size() == 4);
  const std::int64_t expected_stamps[] = {0, step_ns, 4 * step_ns, 7 * step_ns};
  const SE3d* expected_poses[] = {&T0, &T1, &T4, &T7};
  const Vec6 expected_twists[] = {Vec6::Zero(), before, after, Vec6::Zero()};
  const bool twist_known[] = {false, true, true, false};
  for (std::size_t i = 0; i < received.size(); ++i) {
    INFO("message " << i);
    const test::ReceivedOdometry& m = received[i];
    CHECK(std::int64_t{m.sec} * 1'000'000'000 + m.nanosec == expected_stamps[i]);
    CHECK(m.frame_id == "robot1/odom");
    CHECK(m.child_frame_id == "robot1/base_link");
    CHECK(m.position[0] == expected_poses[i]->translation().x());
    CHECK(m.orientation[3] == expected_poses[i]->unitQuaternion().w());
    const Vec6 twist = twistOf(m.linear[0], m.linear[1], m.linear[2], m.angular[0], m.angular[1], m.angular[2]);
    CHECK((twist - expected_twists[i]).norm() < 1e-9);
    CHECK(m.twist_covariance[0] == (twist_known[i] ? 0.0 : -1.0));
  }
}

TEST_CASE("the sink's consume allocates nothing; a full ring drops and counts, finish publishes the rest") {
  const std::string topic = test::uniqueTopicName("odom");
  test::RosSubscriber subscriber(test::useLoopbackDomain());
  const dds_entity_t reader = subscriber.reader(nav_msgs_msg_dds__Odometry__desc, "rt" + topic);
  pipeline::Ros2Sink sink(options(topic), 4);
  REQUIRE(test::RosSubscriber::waitForWriters(reader, 1, std::chrono::seconds(10)));
  std::vector<pipeline::FrameSlot> slots;
  for (int i = 0; i < 7; ++i) {
    slots.push_back(slotAt(i * 50'000'000, SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1 * i, 0.0, 0.0)),
                           TrackingState::kTracking));
  }
  // Not started: nothing takes messages out of the ring, as when the publisher thread falls behind.
  const long allocations_before = test::g_allocations.load();
  for (const pipeline::FrameSlot& slot : slots) sink.consume(slot);
  CHECK(test::g_allocations.load() == allocations_before);
  CHECK(sink.counters().dropped == 3);
  CHECK(sink.counters().published == 0);

  sink.finish();
  CHECK(sink.counters().published == 4);
  test::expectError(sink.summary(), "3 dropped (the publisher fell behind)");
  const std::vector<test::ReceivedOdometry> received =
      test::RosSubscriber::take<test::ReceivedOdometry, nav_msgs_msg_dds__Odometry_>(reader, test::copyOdometry);
  REQUIRE(received.size() == 4);
  for (std::size_t i = 0; i < received.size(); ++i) {
    CHECK(received[i].nanosec == i * 50'000'000);  // the first four: the ring keeps the oldest
    CHECK(received[i].position[0] == 0.1 * static_cast<double>(i));
  }
}

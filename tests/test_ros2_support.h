#pragma once
// A ROS 2 subscriber for the tests, made of the same idlc-generated types as the publisher, and the
// Cyclone DDS settings that let it work where CI runs: loopback only, no multicast, peers found by
// unicast on this host. The same settings with the addresses of a robot's other hosts as peers are
// what a user sets (CYCLONEDDS_URI) on a network without multicast.

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <doctest/doctest.h>
#include <stdlib.h>
#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "nav_msgs.h"
#include "tf2_msgs.h"

namespace voca::test {

// A body-frame twist (linear, angular) as the 6-vector the publisher's velocity helpers take.
using Vec6 = Eigen::Matrix<double, 6, 1>;
inline Vec6 twistOf(double vx, double vy, double vz, double wx, double wy, double wz) {
  Vec6 xi;
  xi << vx, vy, vz, wx, wy, wz;
  return xi;
}

inline constexpr const char* kLoopbackCycloneConfig =
    "<CycloneDDS><Domain id=\"any\">"
    "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
    "<AllowMulticast>false</AllowMulticast></General>"
    "<Discovery><ParticipantIndex>auto</ParticipantIndex><Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
    "</Domain></CycloneDDS>";

// Points Cyclone (in this process and the voca processes it starts) at loopback and a ROS domain of
// its own: a random one of 1..101 (above 101 DDS ports reach Linux's ephemeral range), so test runs
// of other checkouts on this machine publish elsewhere. Returns the domain, also set as ROS_DOMAIN_ID.
inline std::uint32_t useLoopbackDomain() {
  static const std::uint32_t domain = [] {
    std::random_device seed;
    const std::uint32_t d = 1 + seed() % 101;
    setenv("CYCLONEDDS_URI", kLoopbackCycloneConfig, 1);
    setenv("ROS_DOMAIN_ID", std::to_string(d).c_str(), 1);
    return d;
  }();
  return domain;
}

// A topic name no other test run uses: "voca_test_<random>/<leaf>".
inline std::string uniqueTopicName(const std::string& leaf) {
  std::random_device seed;
  return "/voca_test_" + std::to_string(seed()) + "/" + leaf;
}

// A participant with readers that ask for what a ROS 2 subscriber asks: reliable, volatile, XCDR1.
class RosSubscriber {
 public:
  explicit RosSubscriber(std::uint32_t domain) {
    participant_ = dds_create_participant(domain, nullptr, nullptr);
    REQUIRE_MESSAGE(participant_ > 0, "cannot create a DDS participant: " << dds_strretcode(participant_));
  }
  ~RosSubscriber() { dds_delete(participant_); }
  RosSubscriber(const RosSubscriber&) = delete;
  RosSubscriber& operator=(const RosSubscriber&) = delete;

  // A reader on a DDS topic ("rt/odom"). Its history is deep enough for a whole test sequence, so
  // nothing is replaced before the test takes it.
  dds_entity_t reader(const dds_topic_descriptor_t& type, const std::string& dds_topic) {
    const dds_entity_t topic = dds_create_topic(participant_, &type, dds_topic.c_str(), nullptr, nullptr);
    REQUIRE_MESSAGE(topic > 0, "cannot create topic " << dds_topic << ": " << dds_strretcode(topic));
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
    dds_qset_data_representation(qos, 1, &xcdr1);
    const dds_entity_t reader = dds_create_reader(participant_, topic, qos, nullptr);
    dds_delete_qos(qos);
    REQUIRE_MESSAGE(reader > 0, "cannot create a reader of " << dds_topic << ": " << dds_strretcode(reader));
    return reader;
  }

  // Waits until `count` writers are matched to the reader; false after `timeout`.
  static bool waitForWriters(dds_entity_t reader, std::uint32_t count, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      dds_subscription_matched_status_t status{};
      if (dds_get_subscription_matched_status(reader, &status) == DDS_RETCODE_OK && status.current_count >= count) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

  // Takes every sample the reader holds, as the generated C type, deep-copied out of Cyclone's
  // loans: Odometry and TFMessage own strings (and TFMessage a sequence), copied into `Owned`.
  template <typename Owned, typename Message, typename Copy>
  static std::vector<Owned> take(dds_entity_t reader, Copy copy) {
    std::vector<Owned> out;
    for (;;) {
      void* samples[16] = {};
      dds_sample_info_t infos[16];
      const dds_return_t n = dds_take(reader, samples, infos, 16, 16);
      REQUIRE(n >= 0);
      for (dds_return_t i = 0; i < n; ++i) {
        if (infos[i].valid_data) out.push_back(copy(*static_cast<const Message*>(samples[i])));
      }
      dds_return_loan(reader, samples, n);
      if (n < 16) return out;
    }
  }

  // The serialized form of the next sample, as it went on the wire: 4-byte encapsulation header
  // (XCDR1 little-endian: 00 01 00 00) and the CDR data. Empty when the reader holds none.
  static std::vector<unsigned char> takeSerialized(dds_entity_t reader) {
    struct ddsi_serdata* data = nullptr;
    dds_sample_info_t info;
    const dds_return_t n = dds_takecdr(reader, &data, 1, &info, DDS_ANY_STATE);
    REQUIRE(n >= 0);
    if (n == 0) return {};
    std::vector<unsigned char> bytes(ddsi_serdata_size(data));
    ddsi_serdata_to_ser(data, 0, bytes.size(), bytes.data());
    ddsi_serdata_unref(data);
    return bytes;
  }

 private:
  dds_entity_t participant_ = 0;
};

// Plain copies of the received messages.
struct ReceivedOdometry {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string frame_id, child_frame_id;
  double position[3] = {};
  double orientation[4] = {};  // x y z w
  double linear[3] = {}, angular[3] = {};
  double pose_covariance[36] = {}, twist_covariance[36] = {};
};
inline ReceivedOdometry copyOdometry(const nav_msgs_msg_dds__Odometry_& m) {
  ReceivedOdometry r;
  r.sec = m.header.stamp.sec;
  r.nanosec = m.header.stamp.nanosec;
  r.frame_id = m.header.frame_id;
  r.child_frame_id = m.child_frame_id;
  const auto& p = m.pose.pose;
  const double position[3] = {p.position.x, p.position.y, p.position.z};
  const double orientation[4] = {p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w};
  const auto& t = m.twist.twist;
  const double linear[3] = {t.linear.x, t.linear.y, t.linear.z};
  const double angular[3] = {t.angular.x, t.angular.y, t.angular.z};
  std::copy(position, position + 3, r.position);
  std::copy(orientation, orientation + 4, r.orientation);
  std::copy(linear, linear + 3, r.linear);
  std::copy(angular, angular + 3, r.angular);
  std::copy(m.pose.covariance, m.pose.covariance + 36, r.pose_covariance);
  std::copy(m.twist.covariance, m.twist.covariance + 36, r.twist_covariance);
  return r;
}

struct ReceivedTransform {
  std::int32_t sec = 0;
  std::uint32_t nanosec = 0;
  std::string frame_id, child_frame_id;
  double translation[3] = {};
  double rotation[4] = {};  // x y z w
};
// A TFMessage's transforms (ours carry one each).
inline std::vector<ReceivedTransform> copyTransforms(const tf2_msgs_msg_dds__TFMessage_& m) {
  std::vector<ReceivedTransform> out;
  for (std::uint32_t i = 0; i < m.transforms._length; ++i) {
    const geometry_msgs_msg_dds__TransformStamped_& t = m.transforms._buffer[i];
    ReceivedTransform r;
    r.sec = t.header.stamp.sec;
    r.nanosec = t.header.stamp.nanosec;
    r.frame_id = t.header.frame_id;
    r.child_frame_id = t.child_frame_id;
    const double translation[3] = {t.transform.translation.x, t.transform.translation.y, t.transform.translation.z};
    const double rotation[4] = {t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                                t.transform.rotation.w};
    std::copy(translation, translation + 3, r.translation);
    std::copy(rotation, rotation + 4, r.rotation);
    out.push_back(r);
  }
  return out;
}

}  // namespace voca::test

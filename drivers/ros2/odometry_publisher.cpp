#include "drivers/ros2/odometry_publisher.h"

#include <dds/dds.h>
#include <fmt/core.h>

#include <algorithm>
#include <cstdlib>
#include <limits>

#include "drivers/ros2/ros2_names.h"
#include "nav_msgs.h"
#include "tf2_msgs.h"
#include "voca/core/error.h"

namespace voca::ros2 {

namespace {

constexpr std::int64_t kNsPerSecond = 1'000'000'000;
// How long a write may wait for room in a reliable writer's history (DDS's default); keep-last
// writers rarely need any.
constexpr dds_duration_t kMaxBlockingTime = DDS_MSECS(100);

// ROS Time: whole seconds rounded down and the nanoseconds above them (so -0.5 s is sec -1, 5e8 ns).
bool toRosTime(std::int64_t t_ns, builtin_interfaces_msg_dds__Time_& stamp) {
  std::int64_t sec = t_ns / kNsPerSecond;
  std::int64_t nanosec = t_ns % kNsPerSecond;
  if (nanosec < 0) {
    nanosec += kNsPerSecond;
    --sec;
  }
  if (sec < std::numeric_limits<std::int32_t>::min() || sec > std::numeric_limits<std::int32_t>::max()) return false;
  stamp.sec = static_cast<std::int32_t>(sec);
  stamp.nanosec = static_cast<std::uint32_t>(nanosec);
  return true;
}

void setVector(geometry_msgs_msg_dds__Vector3_& out, const Eigen::Vector3d& v) {
  out.x = v.x();
  out.y = v.y();
  out.z = v.z();
}

void setQuaternion(geometry_msgs_msg_dds__Quaternion_& out, const Eigen::Quaterniond& q) {
  out.x = q.x();
  out.y = q.y();
  out.z = q.z();
  out.w = q.w();
}

std::string cycloneConfigNote() {
  const char* uri = std::getenv("CYCLONEDDS_URI");
  return uri != nullptr && *uri != '\0' ? fmt::format("CYCLONEDDS_URI={}", uri)
                                        : std::string("CYCLONEDDS_URI unset: Cyclone's defaults");
}

// Frees a QoS object made with dds_create_qos.
struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// Reliable, volatile, keep-last `depth`, XCDR1: what an rclcpp publisher with the default QoS profile
// (depth 10) or tf2's broadcaster (depth 100) offers, in the data representation rmw_cyclonedds_cpp
// writes (plain CDR, version 1).
QosPtr rosWriterQos(int depth) {
  QosPtr qos(dds_create_qos());
  dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, kMaxBlockingTime);
  dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, depth);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(qos.get(), 1, &xcdr1);
  return qos;
}

}  // namespace

struct OdometryPublisher::Impl {
  std::uint32_t domain_id = 0;
  std::string odometry_topic;  // DDS name
  std::string tf_topic;
  std::string odom_frame, base_frame;
  dds_entity_t participant = 0;
  dds_entity_t odometry_writer = 0;
  dds_entity_t tf_writer = 0;
  nav_msgs_msg_dds__Odometry_ odometry{};
  geometry_msgs_msg_dds__TransformStamped_ transform{};
  tf2_msgs_msg_dds__TFMessage_ tf{};
  std::string last_error;

  ~Impl() {
    if (participant > 0) dds_delete(participant);
  }

  dds_entity_t create(dds_entity_t entity, std::string_view what) {
    if (entity < 0) {
      throw RuntimeFailure(fmt::format("Cyclone DDS could not create the {} in ROS 2 domain {}: {} ({})", what,
                                       domain_id, dds_strretcode(entity), cycloneConfigNote()));
    }
    return entity;
  }

  dds_entity_t writer(const dds_topic_descriptor_t& type, const std::string& topic_name, int depth) {
    const dds_entity_t topic =
        create(dds_create_topic(participant, &type, topic_name.c_str(), nullptr, nullptr), "topic " + topic_name);
    return create(dds_create_writer(participant, topic, rosWriterQos(depth).get(), nullptr), "writer of " + topic_name);
  }
};

OdometryPublisher::OdometryPublisher(const OdometryPublisherOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  if (options.domain_id > kMaxDomainId) {
    throw InputError(fmt::format("ROS 2 domain {}: expected 0 to {}", options.domain_id, kMaxDomainId));
  }
  checkFrameId(options.odom_frame, "odometry frame id");
  checkFrameId(options.base_frame, "base frame id");
  d.domain_id = options.domain_id;
  d.odometry_topic = ddsTopicName(fullyQualifiedTopicName(options.topic, "odometry topic"));
  d.tf_topic = ddsTopicName(kTfTopic);
  d.odom_frame = options.odom_frame;
  d.base_frame = options.base_frame;

  QosPtr participant_qos(dds_create_qos());
  dds_qset_entity_name(participant_qos.get(), "voca");
  d.participant = d.create(dds_create_participant(d.domain_id, participant_qos.get(), nullptr), "participant");
  d.odometry_writer = d.writer(nav_msgs_msg_dds__Odometry__desc, d.odometry_topic, kOdometryHistoryDepth);
  d.tf_writer = d.writer(tf2_msgs_msg_dds__TFMessage__desc, d.tf_topic, kTfHistoryDepth);

  // The parts that never change: frame ids (Cyclone only reads the strings) and covariances. Pose
  // covariance all zero is ROS's "covariance unknown": the estimator computes no calibrated
  // uncertainty, so a filter fusing this odometry has to be given its own noise model.
  d.odometry.header.frame_id = d.odom_frame.data();
  d.odometry.child_frame_id = d.base_frame.data();
  d.transform.header.frame_id = d.odom_frame.data();
  d.transform.child_frame_id = d.base_frame.data();
  d.tf.transforms._maximum = 1;
  d.tf.transforms._length = 1;
  d.tf.transforms._buffer = &d.transform;
  d.tf.transforms._release = false;
}

OdometryPublisher::~OdometryPublisher() = default;

bool OdometryPublisher::publish(const OdometrySample& sample) {
  Impl& d = *impl_;
  if (!toRosTime(sample.t_ns, d.odometry.header.stamp)) {
    d.last_error = fmt::format("stamp {} ns does not fit ROS's Time (int32 seconds)", sample.t_ns);
    return false;
  }
  const Eigen::Vector3d& p = sample.T_odom_base.translation();
  const Eigen::Quaterniond& q = sample.T_odom_base.unitQuaternion();
  d.transform.header.stamp = d.odometry.header.stamp;
  setVector(d.transform.transform.translation, p);
  setQuaternion(d.transform.transform.rotation, q);

  geometry_msgs_msg_dds__Pose_& pose = d.odometry.pose.pose;
  pose.position.x = p.x();
  pose.position.y = p.y();
  pose.position.z = p.z();
  setQuaternion(pose.orientation, q);
  setVector(d.odometry.twist.twist.linear, sample.linear_velocity_mps);
  setVector(d.odometry.twist.twist.angular, sample.angular_velocity_radps);
  // Zero: a velocity with unknown covariance; -1 in element 0: no velocity estimate at all.
  d.odometry.twist.covariance[0] = sample.twist_known ? 0.0 : -1.0;

  // The transform first: a subscriber that looks the odometry up in tf finds its stamp there.
  const dds_return_t tf_rc = dds_write(d.tf_writer, &d.tf);
  const dds_return_t odometry_rc = dds_write(d.odometry_writer, &d.odometry);
  if (tf_rc < 0 || odometry_rc < 0) {
    d.last_error = fmt::format("writing {}: {}", tf_rc < 0 ? d.tf_topic : d.odometry_topic,
                               dds_strretcode(tf_rc < 0 ? tf_rc : odometry_rc));
    return false;
  }
  return true;
}

const std::string& OdometryPublisher::lastError() const { return impl_->last_error; }

bool OdometryPublisher::waitForAcknowledgments(std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const auto remaining = [&] {
    const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - std::chrono::steady_clock::now());
    return static_cast<dds_duration_t>(std::max<std::int64_t>(left.count(), 0));
  };
  const bool tf_acknowledged = dds_wait_for_acks(impl_->tf_writer, remaining()) == DDS_RETCODE_OK;
  const bool odometry_acknowledged = dds_wait_for_acks(impl_->odometry_writer, remaining()) == DDS_RETCODE_OK;
  return tf_acknowledged && odometry_acknowledged;
}

int OdometryPublisher::matchedOdometrySubscribers() const {
  dds_publication_matched_status_t status{};
  if (dds_get_publication_matched_status(impl_->odometry_writer, &status) < 0) return 0;
  return static_cast<int>(status.current_count);
}

const std::string& OdometryPublisher::odometryDdsTopic() const { return impl_->odometry_topic; }

std::uint32_t OdometryPublisher::domainId() const { return impl_->domain_id; }

Eigen::Matrix<double, 6, 1> bodyTwist(const SE3d& T_world_prev, const SE3d& T_world_cur, double dt_s) {
  return (T_world_prev.inverse() * T_world_cur).log() / dt_s;
}

}  // namespace voca::ros2

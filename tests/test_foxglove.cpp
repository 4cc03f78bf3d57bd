// The live view's messages: formats/foxglove's schemas and JSON encoders on known inputs (every message
// valid against its schema, numbers exact to the last digit), and pipeline/sinks/telemetry.h from a
// filled frame slot to every channel's message. test_foxglove_alloc.cpp counts their allocations.

#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "formats/foxglove/foxglove_json.h"
#include "formats/foxglove/foxglove_schemas.h"
#include "pipeline/sinks/telemetry.h"

namespace {

using nlohmann::json;
using voca::SE3d;
namespace fg = voca::foxglove;

// The part of JSON Schema our schemas use: type, properties, items, oneOf of consts, enum, minimum,
// maximum. Appends one line per violation.
void validate(const json& value, const json& schema, const std::string& path, std::vector<std::string>& errors) {
  if (schema.contains("oneOf")) {
    const bool any = std::any_of(schema["oneOf"].begin(), schema["oneOf"].end(), [&](const json& option) {
      return option.contains("const") && option["const"] == value;
    });
    if (!any) errors.push_back(path + ": not one of the oneOf constants");
    return;
  }
  if (schema.contains("enum") &&
      std::find(schema["enum"].begin(), schema["enum"].end(), value) == schema["enum"].end()) {
    errors.push_back(path + ": not in the enum");
  }
  if (schema.contains("type")) {
    const std::string type = schema["type"];
    const bool ok = (type == "object" && value.is_object()) || (type == "array" && value.is_array()) ||
                    (type == "string" && value.is_string()) || (type == "boolean" && value.is_boolean()) ||
                    (type == "integer" && value.is_number_integer()) || (type == "number" && value.is_number());
    if (!ok) {
      errors.push_back(path + ": expected " + type + ", got " + value.dump().substr(0, 40));
      return;
    }
  }
  if (value.is_number()) {
    if (schema.contains("minimum") && value.get<double>() < schema["minimum"].get<double>()) {
      errors.push_back(path + ": below its minimum");
    }
    if (schema.contains("maximum") && value.get<double>() > schema["maximum"].get<double>()) {
      errors.push_back(path + ": above its maximum");
    }
  }
  if (value.is_object() && schema.contains("properties")) {
    for (const auto& [key, item] : value.items()) {
      if (!schema["properties"].contains(key)) {
        errors.push_back(path + "." + key + ": not in the schema");
        continue;
      }
      validate(item, schema["properties"][key], path + "." + key, errors);
    }
  }
  if (value.is_array() && schema.contains("items")) {
    for (std::size_t i = 0; i < value.size(); ++i) {
      validate(value[i], schema["items"], path + "[" + std::to_string(i) + "]", errors);
    }
  }
}

// Parses a message and checks it against its schema; returns the parsed message.
json checkedMessage(const std::string& text, fg::SchemaId id) {
  const json message = json::parse(text);
  std::vector<std::string> errors;
  validate(message, json::parse(fg::schema(id).text), "", errors);
  INFO(fg::schema(id).name << ": " << text.substr(0, 300));
  for (const std::string& error : errors) CHECK_MESSAGE(false, error);
  return message;
}

std::vector<std::uint8_t> fromBase64(const std::string& text) {
  std::vector<std::uint8_t> out;
  std::uint32_t buffer = 0;
  int bits = 0;
  for (const char c : text) {
    if (c == '=') break;
    const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* at = std::strchr(alphabet, c);
    REQUIRE(at != nullptr);
    buffer = (buffer << 6) | static_cast<std::uint32_t>(at - alphabet);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>(buffer >> bits));
    }
  }
  return out;
}

SE3d poseOf(double x, double y, double z, double angle) {
  return SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d(0.3, -0.5, 0.8).normalized())),
              Eigen::Vector3d(x, y, z));
}

}  // namespace

TEST_CASE("base64 as RFC 4648's test vectors") {
  const std::map<std::string, std::string> vectors = {{"", ""},
                                                      {"f", "Zg=="},
                                                      {"fo", "Zm8="},
                                                      {"foo", "Zm9v"},
                                                      {"foob", "Zm9vYg=="},
                                                      {"fooba", "Zm9vYmE="},
                                                      {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, encoded] : vectors) {
    std::string out = "x";
    fg::appendBase64({reinterpret_cast<const std::uint8_t*>(plain.data()), plain.size()}, out);
    CHECK(out == "x" + encoded);
    CHECK(fg::base64Size(plain.size()) == encoded.size());
  }
}

TEST_CASE("every schema is a JSON object schema titled with its name") {
  CHECK(fg::allSchemas().size() == 7);
  for (const fg::Schema& s : fg::allSchemas()) {
    INFO(s.name);
    const json doc = json::parse(s.text);  // throws on a syntax error
    CHECK(doc["title"] == std::string(s.name));
    CHECK(doc["type"] == "object");
    CHECK(doc["properties"].is_object());
    CHECK(&fg::schema(s.id) == &s);
  }
  // The byte fields are marked base64, which is how Foxglove's JSON reader knows to decode them.
  CHECK(json::parse(fg::schema(fg::SchemaId::kCompressedImage).text)["properties"]["data"]["contentEncoding"] ==
        "base64");
  CHECK(json::parse(fg::schema(fg::SchemaId::kPointCloud).text)["properties"]["data"]["contentEncoding"] == "base64");
}

TEST_CASE("pose, transform and path: exact numbers, times split into sec and nsec, valid against their schemas") {
  const SE3d pose = poseOf(1.0 / 3.0, -2.5e-7, 12345.678901234567, 0.7);
  std::string out;
  fg::writePoseInFrame(1'234'567'890'123, "odom", pose, out);
  const json m = checkedMessage(out, fg::SchemaId::kPoseInFrame);
  CHECK(m["timestamp"]["sec"] == 1234);
  CHECK(m["timestamp"]["nsec"] == 567'890'123);
  CHECK(m["frame_id"] == "odom");
  // Shortest round-trip text: reading it back gives the very same doubles.
  CHECK(m["pose"]["position"]["x"].get<double>() == pose.translation().x());
  CHECK(m["pose"]["position"]["y"].get<double>() == pose.translation().y());
  CHECK(m["pose"]["position"]["z"].get<double>() == pose.translation().z());
  CHECK(m["pose"]["orientation"]["w"].get<double>() == pose.unitQuaternion().w());
  CHECK(m["pose"]["orientation"]["x"].get<double>() == pose.unitQuaternion().x());

  fg::writeFrameTransform(-5, "odom", "base_link", pose, out);
  const json t = checkedMessage(out, fg::SchemaId::kFrameTransform);
  CHECK(t["timestamp"]["sec"] == 0);  // negative times: 0 (the schema's minimum)
  CHECK(t["timestamp"]["nsec"] == 0);
  CHECK(t["parent_frame_id"] == "odom");
  CHECK(t["child_frame_id"] == "base_link");
  CHECK(t["rotation"]["z"].get<double>() == pose.unitQuaternion().z());

  const std::vector<SE3d> path = {SE3d(), pose, poseOf(1, 2, 3, -0.1)};
  fg::writePosesInFrame(7, "odom", path, out);
  const json p = checkedMessage(out, fg::SchemaId::kPosesInFrame);
  REQUIRE(p["poses"].size() == 3);
  CHECK(p["poses"][2]["position"]["y"].get<double>() == 2.0);
  CHECK(p["poses"][0]["orientation"]["w"].get<double>() == 1.0);

  // A diverged estimate stays valid JSON.
  SE3d broken;
  broken.translation().x() = std::nan("");
  fg::writePoseInFrame(0, "odom", broken, out);
  CHECK(json::parse(out)["pose"]["position"]["x"].is_null());
}

TEST_CASE("image, point cloud, motion vectors and statistics round-trip through their JSON") {
  std::string out;
  const std::vector<std::uint8_t> jpeg = {0xff, 0xd8, 0xff, 0xe0, 0x00, 0x10, 0x4a};
  fg::writeCompressedImage(3'000'000'001, "cam0", "jpeg", jpeg, out);
  const json image = checkedMessage(out, fg::SchemaId::kCompressedImage);
  CHECK(image["format"] == "jpeg");
  CHECK(fromBase64(image["data"]) == jpeg);
  CHECK(image["timestamp"]["sec"] == 3);
  CHECK(image["timestamp"]["nsec"] == 1);

  const std::vector<Eigen::Vector3f> points = {{1.5f, -2.25f, 3.0f}, {0.1f, 0.2f, -0.3f}, {1e-3f, 4e4f, 7.f}};
  fg::writePointCloud(1, "odom", points, out);
  const json cloud = checkedMessage(out, fg::SchemaId::kPointCloud);
  CHECK(cloud["point_stride"] == 12);
  REQUIRE(cloud["fields"].size() == 3);
  CHECK(cloud["fields"][2]["name"] == "z");
  CHECK(cloud["fields"][2]["offset"] == 8);
  const std::vector<std::uint8_t> bytes = fromBase64(cloud["data"]);
  REQUIRE(bytes.size() == points.size() * 12);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      std::uint32_t bits = 0;  // little-endian, as the schema's NumericType says
      for (int b = 0; b < 4; ++b) bits |= std::uint32_t{bytes[i * 12 + 4 * static_cast<std::size_t>(k) + b]} << (8 * b);
      float value = 0.f;
      std::memcpy(&value, &bits, sizeof value);
      CHECK(value == points[i][k]);
    }
  }

  voca::MotionField field(64, 32);
  field.reset(64, 32, voca::PictureType::kP);
  REQUIRE(field.addBlock(0, 0, 16, 16, 4.f, -2.f));  // inlier: (3.5, 9.5) -> (8, 8) after +0.5 to corners
  REQUIRE(field.addBlock(16, 0, 16, 16, 0.f, 0.f));  // zero: left out
  REQUIRE(field.addBlock(32, 0, 16, 16, 1.f, 1.f));  // outlier (flagged below)
  REQUIRE(field.addBlock(48, 0, 16, 16, 2.f, 2.f, voca::RefDirection::kFuture));  // left out
  field.finalize();
  field.blocks()[2].outlier = true;
  fg::writeMotionVectorAnnotations(5, field.blocks(), out);
  const json annotations = checkedMessage(out, fg::SchemaId::kImageAnnotations);
  REQUIRE(annotations["points"].size() == 2);
  const json& inliers = annotations["points"][0];
  CHECK(inliers["type"] == 4);  // LINE_LIST
  REQUIRE(inliers["points"].size() == 2);
  CHECK(inliers["points"][0]["x"].get<double>() == doctest::Approx(4.0));
  CHECK(inliers["points"][0]["y"].get<double>() == doctest::Approx(10.0));
  CHECK(inliers["points"][1]["x"].get<double>() == doctest::Approx(8.0));
  CHECK(inliers["points"][1]["y"].get<double>() == doctest::Approx(8.0));
  const json& outliers = annotations["points"][1];
  REQUIRE(outliers["points"].size() == 2);
  CHECK(outliers["outline_color"]["r"].get<double>() == 1.0);
  CHECK(outliers["points"][1]["x"].get<double>() == doctest::Approx(40.0));

  fg::FrameStats stats;
  stats.t_ns = 42;
  stats.frame_index = 17;
  stats.state = "reset";
  stats.keyframe = true;
  stats.decode_ms = 0.5;
  stats.frontend_ms = 6.25;
  stats.backend_ms = 1.125;
  stats.end_to_end_ms = 9.0;
  stats.tracks_left = 200;
  stats.tracks_right = 150;
  stats.dropped = 3;
  stats.damaged = 1;
  stats.view_dropped = 2;
  fg::writeFrameStats(stats, out);
  const json s = checkedMessage(out, fg::SchemaId::kFrameStats);
  CHECK(s["frame"] == 17);
  CHECK(s["state"] == "reset");
  CHECK(s["latency_ms"]["frontend"].get<double>() == 6.25);
  CHECK(s["tracks"]["right"] == 150);
  CHECK(s["dropped"] == 3);
  CHECK(s["damaged"] == 1);
  CHECK(s["view_dropped"] == 2);
}

TEST_CASE("a decimated path keeps a bounded, evenly spaced subset that ends at the newest pose") {
  voca::pipeline::DecimatedPath path(8);
  const auto xOf = [](const SE3d& pose) { return static_cast<int>(pose.translation().x()); };
  for (int i = 0; i < 8; ++i) path.add(SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(i, 0, 0)));
  REQUIRE(path.poses().size() == 8);  // everything while it fits
  CHECK(path.stride() == 1);
  for (int i = 8; i < 100; ++i) {
    path.add(SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(i, 0, 0)));
    const auto poses = path.poses();
    INFO("after pose " << i);
    REQUIRE(poses.size() <= 9);
    CHECK(xOf(poses.front()) == 0);
    CHECK(xOf(poses.back()) == i);
    // Every kept pose but the newest sits on the stride.
    for (std::size_t k = 0; k + 1 < poses.size(); ++k) {
      CHECK(xOf(poses[k]) == static_cast<int>(k * path.stride()));
    }
  }
  CHECK(path.stride() == 16);
}

TEST_CASE("telemetry: a finished frame becomes one message per wanted channel") {
  constexpr int kWidth = 64, kHeight = 48, kPoints = 10, kLandmarks = 20;
  voca::pipeline::FrameSlot slot;
  slot.reserve(kWidth, kHeight, kPoints, kLandmarks);
  slot.frame.t_ns = 5'000'000'123;
  slot.frame.frame_index = 9;
  for (voca::GrayImage& image : slot.frame.images) {
    image.resize(kWidth, kHeight);
    for (int y = 0; y < kHeight; ++y)
      for (int x = 0; x < kWidth; ++x) image(x, y) = static_cast<std::uint8_t>((x * 7 + y * 3) % 256);
  }
  slot.frame.has_motion = true;
  slot.frame.motion[0].reset(kWidth, kHeight, voca::PictureType::kP);
  slot.frame.motion[0].addBlock(0, 0, 16, 16, 2.f, 1.f);
  slot.frame.motion[0].finalize();
  slot.tracked.observations[0].push_back({1, Eigen::Vector2f(10.f, 12.f)});
  slot.tracked.observations[1].push_back({1, Eigen::Vector2f(8.f, 12.f)});
  slot.left_traces.push_back({1, {9.f, 11.f}, {9.5f, 11.5f}, {10.f, 12.f}, true, true});
  slot.landmarks_world.push_back({1.f, 2.f, 3.f});
  slot.pose.T_world_body = poseOf(0.5, -0.25, 2.0, 0.3);
  slot.pose.state = voca::TrackingState::kTracking;
  slot.pose.num_landmarks = 1;
  slot.arrival_ns = 1'000'000;
  slot.timing[1] = {1'000'000, 2'000'000, 0, 0};  // decode 1 ms
  slot.timing[2] = {2'000'000, 8'000'000, 0, 0};  // frontend 6 ms
  slot.timing[3] = {8'000'000, 9'500'000, 0, 0};  // backend 1.5 ms
  slot.timing[4] = {10'000'000, 0, 0, 0};         // the sinks got it 9 ms after arrival
  slot.dropped_so_far = 2;
  slot.damaged_so_far = 1;
  const voca::pipeline::StagePositions stages{.decode = 1, .frontend = 2, .backend = 3, .write = 4};

  // The ground truth: the estimate's motion seen from another world frame; aligned at the first frame,
  // its path must coincide with the estimate's.
  const SE3d T_gtworld_odom = poseOf(10, 20, 30, 1.0);
  voca::Trajectory gt;
  for (int k = 0; k < 3; ++k) {
    gt.poses.push_back({5'000'000'123 + k * 50'000'000, T_gtworld_odom * poseOf(0.5 + k * 0.1, -0.25, 2.0, 0.3)});
  }

  voca::pipeline::TelemetrySnapshot snapshot;
  snapshot.reserve(kWidth, kHeight, kPoints, kLandmarks);
  voca::pipeline::TelemetryChannels all;
  all.set();
  voca::pipeline::captureTelemetry(slot, stages, all, snapshot);
  CHECK(snapshot.frontend_ms == doctest::Approx(6.0));
  CHECK(snapshot.end_to_end_ms == doctest::Approx(9.0));
  CHECK(snapshot.motion_blocks.size() == 1);

  voca::pipeline::TelemetryEncoder encoder(
      {.width = kWidth, .height = kHeight, .max_points = kPoints, .max_landmarks = kLandmarks, .ground_truth = &gt});
  std::map<voca::pipeline::TelemetryChannel, json> messages;
  const voca::pipeline::TelemetryEncoder::Publish collect = [&](voca::pipeline::TelemetryChannel channel,
                                                                std::int64_t t_ns, std::string_view payload) {
    CHECK(t_ns == slot.frame.t_ns);
    CHECK(messages.count(channel) == 0);
    const voca::pipeline::TelemetryChannelInfo& info = voca::pipeline::telemetryChannels()[static_cast<int>(channel)];
    messages[channel] = checkedMessage(std::string(payload), info.schema);
  };
  encoder.encode(snapshot, collect);
  using C = voca::pipeline::TelemetryChannel;
  CHECK(messages.size() == static_cast<std::size_t>(voca::pipeline::kTelemetryChannelCount));
  const std::vector<std::uint8_t> jpeg = fromBase64(messages[C::kImage]["data"]);
  REQUIRE(jpeg.size() > 100);
  CHECK(jpeg[0] == 0xff);  // a JPEG file: SOI marker
  CHECK(jpeg[1] == 0xd8);
  CHECK(messages[C::kPose]["pose"]["position"]["z"].get<double>() == 2.0);
  CHECK(messages[C::kTransform]["child_frame_id"] == "base_link");
  CHECK(messages[C::kPath]["poses"].size() == 1);
  CHECK(messages[C::kLandmarks]["data"] == "AACAPwAAAEAAAEBA");  // 1, 2, 3 as little-endian float32
  CHECK(messages[C::kFrameStats]["latency_ms"]["backend"].get<double>() == doctest::Approx(1.5));
  CHECK(messages[C::kFrameStats]["dropped"] == 2);
  CHECK(messages[C::kFrameStats]["damaged"] == 1);
  CHECK(messages[C::kMotionVectors]["points"][0]["points"].size() == 2);

  // Two more frames: the paths grow by each pose, the ground truth's matching the estimate's.
  for (int k = 1; k < 3; ++k) {
    slot.frame.t_ns = 5'000'000'123 + k * 50'000'000;
    slot.pose.T_world_body = poseOf(0.5 + k * 0.1, -0.25, 2.0, 0.3);
    voca::pipeline::TelemetryChannels paths;
    paths.set(voca::pipeline::channelBit(C::kPath));
    paths.set(voca::pipeline::channelBit(C::kGroundTruthPath));
    voca::pipeline::captureTelemetry(slot, stages, paths, snapshot);
    messages.clear();
    encoder.encode(snapshot, collect);
    CHECK(messages.size() == 2);  // only what the snapshot asked for
  }
  const json& estimate = messages[C::kPath]["poses"];
  const json& truth = messages[C::kGroundTruthPath]["poses"];
  REQUIRE(estimate.size() == 3);
  REQUIRE(truth.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    for (const char* axis : {"x", "y", "z"}) {
      CHECK(truth[k]["position"][axis].get<double>() ==
            doctest::Approx(estimate[k]["position"][axis].get<double>()).epsilon(1e-12));
    }
  }
}

#include "formats/foxglove/foxglove_json.h"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <iterator>

namespace voca::foxglove {

namespace {

// The longest number fmt writes for a double ("-2.2250738585072014e-308") and a float.
constexpr std::size_t kMaxDoubleChars = 24;
constexpr std::size_t kMaxFloatChars = 15;
// {"position":{"x":,"y":,"z":},"orientation":{"x":,"y":,"z":,"w":}} with seven numbers.
constexpr std::size_t kPoseMaxBytes = 72 + 7 * kMaxDoubleChars;
// {"x":,"y":}, twice per segment, with its comma.
constexpr std::size_t kSegmentMaxBytes = 2 * (14 + 2 * kMaxFloatChars);
// Everything around the variable part of a message: keys, time, frame ids, fields.
constexpr std::size_t kEnvelopeMaxBytes = 600;

class JsonWriter {
 public:
  explicit JsonWriter(std::string& out) : out_(out) { out_.clear(); }

  void raw(std::string_view text) { out_.append(text); }
  void number(double value) {
    if (std::isfinite(value)) {
      fmt::format_to(std::back_inserter(out_), "{}", value);
    } else {
      out_.append("null");
    }
  }
  void number(float value) {
    if (std::isfinite(value)) {
      fmt::format_to(std::back_inserter(out_), "{}", value);
    } else {
      out_.append("null");
    }
  }
  void integer(std::int64_t value) { fmt::format_to(std::back_inserter(out_), "{}", value); }
  void boolean(bool value) { out_.append(value ? "true" : "false"); }
  // A JSON string; our strings are identifiers, but anything is escaped correctly.
  void string(std::string_view text) {
    out_.push_back('"');
    for (const char c : text) {
      if (c == '"' || c == '\\') {
        out_.push_back('\\');
        out_.push_back(c);
      } else if (static_cast<unsigned char>(c) < 0x20) {
        fmt::format_to(std::back_inserter(out_), "\\u{:04x}", static_cast<unsigned>(c));
      } else {
        out_.push_back(c);
      }
    }
    out_.push_back('"');
  }
  void time(std::int64_t t_ns) {
    const std::int64_t clamped = t_ns < 0 ? 0 : t_ns;
    fmt::format_to(std::back_inserter(out_), R"({{"sec":{},"nsec":{}}})", clamped / 1'000'000'000,
                   clamped % 1'000'000'000);
  }
  void vector3(const Eigen::Vector3d& v) {
    raw(R"({"x":)");
    number(v.x());
    raw(R"(,"y":)");
    number(v.y());
    raw(R"(,"z":)");
    number(v.z());
    raw("}");
  }
  void quaternion(const Eigen::Quaterniond& q) {
    raw(R"({"x":)");
    number(q.x());
    raw(R"(,"y":)");
    number(q.y());
    raw(R"(,"z":)");
    number(q.z());
    raw(R"(,"w":)");
    number(q.w());
    raw("}");
  }
  void pose(const SE3d& pose) {
    raw(R"({"position":)");
    vector3(pose.translation());
    raw(R"(,"orientation":)");
    quaternion(pose.unitQuaternion());
    raw("}");
  }
  void point2(float x, float y) {
    raw(R"({"x":)");
    number(x);
    raw(R"(,"y":)");
    number(y);
    raw("}");
  }
  std::string& out() { return out_; }

 private:
  std::string& out_;
};

constexpr char kBase64Alphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

}  // namespace

void appendBase64(std::span<const std::uint8_t> bytes, std::string& out) {
  const std::size_t start = out.size();
  out.resize(start + base64Size(bytes.size()));
  char* dst = out.data() + start;
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    *dst++ = kBase64Alphabet[(v >> 18) & 63];
    *dst++ = kBase64Alphabet[(v >> 12) & 63];
    *dst++ = kBase64Alphabet[(v >> 6) & 63];
    *dst++ = kBase64Alphabet[v & 63];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    std::uint32_t v = std::uint32_t{bytes[i]} << 16;
    if (rest == 2) v |= std::uint32_t{bytes[i + 1]} << 8;
    *dst++ = kBase64Alphabet[(v >> 18) & 63];
    *dst++ = kBase64Alphabet[(v >> 12) & 63];
    *dst++ = rest == 2 ? kBase64Alphabet[(v >> 6) & 63] : '=';
    *dst++ = '=';
  }
}

void writeCompressedImage(std::int64_t t_ns, std::string_view frame_id, std::string_view format,
                          std::span<const std::uint8_t> data, std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"timestamp":)");
  w.time(t_ns);
  w.raw(R"(,"frame_id":)");
  w.string(frame_id);
  w.raw(R"(,"format":)");
  w.string(format);
  w.raw(R"(,"data":")");
  appendBase64(data, w.out());
  w.raw(R"("})");
}

std::size_t compressedImageMaxBytes(std::size_t data_bytes) { return kEnvelopeMaxBytes + base64Size(data_bytes); }

void writePoseInFrame(std::int64_t t_ns, std::string_view frame_id, const SE3d& pose, std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"timestamp":)");
  w.time(t_ns);
  w.raw(R"(,"frame_id":)");
  w.string(frame_id);
  w.raw(R"(,"pose":)");
  w.pose(pose);
  w.raw("}");
}

void writePosesInFrame(std::int64_t t_ns, std::string_view frame_id, std::span<const SE3d> poses, std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"timestamp":)");
  w.time(t_ns);
  w.raw(R"(,"frame_id":)");
  w.string(frame_id);
  w.raw(R"(,"poses":[)");
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (i > 0) w.raw(",");
    w.pose(poses[i]);
  }
  w.raw("]}");
}

std::size_t posesInFrameMaxBytes(std::size_t poses) { return kEnvelopeMaxBytes + poses * (kPoseMaxBytes + 1); }

void writeFrameTransform(std::int64_t t_ns, std::string_view parent_frame_id, std::string_view child_frame_id,
                         const SE3d& T_parent_child, std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"timestamp":)");
  w.time(t_ns);
  w.raw(R"(,"parent_frame_id":)");
  w.string(parent_frame_id);
  w.raw(R"(,"child_frame_id":)");
  w.string(child_frame_id);
  w.raw(R"(,"translation":)");
  w.vector3(T_parent_child.translation());
  w.raw(R"(,"rotation":)");
  w.quaternion(T_parent_child.unitQuaternion());
  w.raw("}");
}

void writePointCloud(std::int64_t t_ns, std::string_view frame_id, std::span<const Eigen::Vector3f> points,
                     std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"timestamp":)");
  w.time(t_ns);
  w.raw(R"(,"frame_id":)");
  w.string(frame_id);
  // FLOAT32 is type 7 of foxglove.NumericType.
  w.raw(
      R"(,"pose":{"position":{"x":0,"y":0,"z":0},"orientation":{"x":0,"y":0,"z":0,"w":1}},"point_stride":12,)"
      R"("fields":[{"name":"x","offset":0,"type":7},{"name":"y","offset":4,"type":7},{"name":"z","offset":8,"type":7}],)"
      R"("data":")");
  // Base64 of the packed little-endian floats, three bytes of input at a time, straight from the
  // points (no intermediate byte buffer to own).
  std::string& s = w.out();
  const std::size_t bytes = points.size() * 12;
  const std::size_t start = s.size();
  s.resize(start + base64Size(bytes));
  char* dst = s.data() + start;
  const auto byteAt = [&](std::size_t k) -> std::uint8_t {
    const float value = points[k / 12][static_cast<Eigen::Index>((k % 12) / 4)];
    std::uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    return static_cast<std::uint8_t>(bits >> (8 * (k % 4)));
  };
  // 12 bytes a point: always a multiple of 3, so no padding.
  for (std::size_t k = 0; k < bytes; k += 3) {
    const std::uint32_t v = (std::uint32_t{byteAt(k)} << 16) | (std::uint32_t{byteAt(k + 1)} << 8) | byteAt(k + 2);
    *dst++ = kBase64Alphabet[(v >> 18) & 63];
    *dst++ = kBase64Alphabet[(v >> 12) & 63];
    *dst++ = kBase64Alphabet[(v >> 6) & 63];
    *dst++ = kBase64Alphabet[v & 63];
  }
  w.raw(R"("})");
}

std::size_t pointCloudMaxBytes(std::size_t points) { return kEnvelopeMaxBytes + base64Size(points * 12); }

void writeMotionVectorAnnotations(std::int64_t t_ns, std::span<const MotionBlock> blocks, std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"circles":[],"texts":[],"points":[)");
  // Foxglove's image coordinates start at the top-left corner of the top-left pixel; ours at its centre.
  constexpr float kToCorner = 0.5f;
  for (const bool outliers : {false, true}) {
    if (outliers) w.raw(",");
    w.raw(R"({"timestamp":)");
    w.time(t_ns);
    w.raw(R"(,"type":4,"points":[)");  // LINE_LIST: segments 0-1, 2-3, ...
    bool first = true;
    for (const MotionBlock& b : blocks) {
      if (b.ref != RefDirection::kPast || b.outlier != outliers || (b.dx == 0.f && b.dy == 0.f)) continue;
      if (!first) w.raw(",");
      first = false;
      const float x = b.centreX() + kToCorner, y = b.centreY() + kToCorner;
      w.point2(x - b.dx, y - b.dy);
      w.raw(",");
      w.point2(x, y);
    }
    w.raw(outliers ? R"(],"outline_color":{"r":1,"g":0.16,"b":0.16,"a":1})"
                   : R"(],"outline_color":{"r":0.16,"g":0.9,"b":0.24,"a":1})");
    w.raw(R"(,"outline_colors":[],"fill_color":{"r":0,"g":0,"b":0,"a":0},"thickness":1})");
  }
  w.raw("]}");
}

std::size_t motionVectorAnnotationsMaxBytes(std::size_t blocks) {
  return 2 * kEnvelopeMaxBytes + blocks * kSegmentMaxBytes;
}

void writeFrameStats(const FrameStats& s, std::string& out) {
  JsonWriter w(out);
  w.raw(R"({"timestamp":)");
  w.time(s.t_ns);
  w.raw(R"(,"frame":)");
  w.integer(s.frame_index);
  w.raw(R"(,"state":)");
  w.string(s.state);
  w.raw(R"(,"keyframe":)");
  w.boolean(s.keyframe);
  w.raw(R"(,"latency_ms":{"decode":)");
  w.number(s.decode_ms);
  w.raw(R"(,"frontend":)");
  w.number(s.frontend_ms);
  w.raw(R"(,"backend":)");
  w.number(s.backend_ms);
  w.raw(R"(,"end_to_end":)");
  w.number(s.end_to_end_ms);
  w.raw(R"(},"tracks":{"left":)");
  w.integer(s.tracks_left);
  w.raw(R"(,"right":)");
  w.integer(s.tracks_right);
  w.raw(R"(},"landmarks":)");
  w.integer(s.landmarks);
  w.raw(R"(,"keyframes":)");
  w.integer(s.keyframes);
  w.raw(R"(,"inliers":)");
  w.integer(s.inliers);
  w.raw(R"(,"dropped":)");
  w.integer(s.dropped);
  w.raw(R"(,"damaged":)");
  w.integer(s.damaged);
  w.raw(R"(,"view_dropped":)");
  w.integer(s.view_dropped);
  w.raw("}");
}

}  // namespace voca::foxglove

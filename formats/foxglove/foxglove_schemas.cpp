#include "formats/foxglove/foxglove_schemas.h"

#include <array>

namespace voca::foxglove {

namespace {

// Fragments shared by several schemas, joined by the compiler (adjacent string literals), so every
// document is one constant with no start-up work.
#define VOCA_SCHEMA_TIME \
  R"({"type": "object", "title": "time", "properties": {"sec": {"type": "integer", "minimum": 0}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}})"
#define VOCA_SCHEMA_VECTOR3 \
  R"({"title": "foxglove.Vector3", "type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}})"
#define VOCA_SCHEMA_QUATERNION \
  R"({"title": "foxglove.Quaternion", "type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}}})"
#define VOCA_SCHEMA_POSE                                                                            \
  R"({"title": "foxglove.Pose", "type": "object", "properties": {"position": )" VOCA_SCHEMA_VECTOR3 \
  R"(, "orientation": )" VOCA_SCHEMA_QUATERNION R"(}})"
#define VOCA_SCHEMA_COLOR \
  R"({"title": "foxglove.Color", "type": "object", "properties": {"r": {"type": "number"}, "g": {"type": "number"}, "b": {"type": "number"}, "a": {"type": "number"}}})"
#define VOCA_SCHEMA_POINT2 \
  R"({"title": "foxglove.Point2", "type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}}})"

constexpr std::string_view kCompressedImage =
    R"({"title": "foxglove.CompressedImage", "description": "A compressed image: the left camera with its tracks drawn", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME R"(, "frame_id": {"type": "string"}, )"
    R"("data": {"type": "string", "contentEncoding": "base64", "description": "Compressed image data"}, )"
    R"("format": {"type": "string", "description": "Image format: jpeg"}}})";

constexpr std::string_view kImageAnnotations =
    R"({"title": "foxglove.ImageAnnotations", "description": "Annotations on a 2D image: the codec's motion vectors", "type": "object", "properties": {)"
    R"("circles": {"type": "array", "items": {"title": "foxglove.CircleAnnotation", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME R"(, "position": )" VOCA_SCHEMA_POINT2
    R"(, "diameter": {"type": "number"}, "thickness": {"type": "number"}, "fill_color": )" VOCA_SCHEMA_COLOR
    R"(, "outline_color": )" VOCA_SCHEMA_COLOR R"(}}}, )"
    R"("points": {"type": "array", "items": {"title": "foxglove.PointsAnnotation", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME
    R"(, "type": {"title": "foxglove.PointsAnnotationType", "oneOf": [{"title": "UNKNOWN", "const": 0}, {"title": "POINTS", "const": 1}, {"title": "LINE_LOOP", "const": 2}, {"title": "LINE_STRIP", "const": 3}, {"title": "LINE_LIST", "const": 4}]}, )"
    R"("points": {"type": "array", "items": )" VOCA_SCHEMA_POINT2 R"(}, "outline_color": )" VOCA_SCHEMA_COLOR
    R"(, "outline_colors": {"type": "array", "items": )" VOCA_SCHEMA_COLOR R"(}, "fill_color": )" VOCA_SCHEMA_COLOR
    R"(, "thickness": {"type": "number"}}}}, )"
    R"("texts": {"type": "array", "items": {"title": "foxglove.TextAnnotation", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME R"(, "position": )" VOCA_SCHEMA_POINT2
    R"(, "text": {"type": "string"}, "font_size": {"type": "number"}, "text_color": )" VOCA_SCHEMA_COLOR
    R"(, "background_color": )" VOCA_SCHEMA_COLOR R"(}}}}})";

constexpr std::string_view kPoseInFrame =
    R"({"title": "foxglove.PoseInFrame", "description": "The body's current pose in the odometry frame", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME R"(, "frame_id": {"type": "string"}, "pose": )" VOCA_SCHEMA_POSE R"(}})";

constexpr std::string_view kPosesInFrame =
    R"({"title": "foxglove.PosesInFrame", "description": "A path: body poses in the odometry frame, oldest first", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME
    R"(, "frame_id": {"type": "string"}, "poses": {"type": "array", "items": )" VOCA_SCHEMA_POSE R"(}}})";

constexpr std::string_view kFrameTransform =
    R"({"title": "foxglove.FrameTransform", "description": "A transform from the parent frame to the child frame", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME
    R"(, "parent_frame_id": {"type": "string"}, "child_frame_id": {"type": "string"}, "translation": )" VOCA_SCHEMA_VECTOR3
    R"(, "rotation": )" VOCA_SCHEMA_QUATERNION R"(}})";

constexpr std::string_view kPointCloud =
    R"({"title": "foxglove.PointCloud", "description": "Points packed in a byte array: the estimator's landmarks", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME R"(, "frame_id": {"type": "string"}, "pose": )" VOCA_SCHEMA_POSE
    R"(, "point_stride": {"type": "integer", "minimum": 0}, )"
    R"("fields": {"type": "array", "items": {"title": "foxglove.PackedElementField", "type": "object", "properties": {)"
    R"("name": {"type": "string"}, "offset": {"type": "integer", "minimum": 0}, )"
    R"("type": {"title": "foxglove.NumericType", "oneOf": [{"title": "UNKNOWN", "const": 0}, {"title": "UINT8", "const": 1}, {"title": "INT8", "const": 2}, {"title": "UINT16", "const": 3}, {"title": "INT16", "const": 4}, {"title": "UINT32", "const": 5}, {"title": "INT32", "const": 6}, {"title": "FLOAT32", "const": 7}, {"title": "FLOAT64", "const": 8}]}}}}, )"
    R"("data": {"type": "string", "contentEncoding": "base64"}}})";

constexpr std::string_view kFrameStats =
    R"({"title": "voca.FrameStats", "description": "One frame through the VOCA-RT pipeline: latency per stage, tracks, the estimator's window, skipped frames", "type": "object", "properties": {)"
    R"("timestamp": )" VOCA_SCHEMA_TIME R"(, )"
    R"("frame": {"type": "integer", "description": "Index of the frame in the source"}, )"
    R"("state": {"type": "string", "enum": ["tracking", "reset", "lost"]}, )"
    R"("keyframe": {"type": "boolean"}, )"
    R"("latency_ms": {"type": "object", "description": "Milliseconds per stage; decode is 0 for raw images; end_to_end from the frame's arrival to its pose reaching the sinks", "properties": {)"
    R"("decode": {"type": "number"}, "frontend": {"type": "number"}, "backend": {"type": "number"}, "end_to_end": {"type": "number"}}}, )"
    R"("tracks": {"type": "object", "properties": {"left": {"type": "integer"}, "right": {"type": "integer"}}}, )"
    R"("landmarks": {"type": "integer", "description": "Alive in the estimator's window"}, )"
    R"("keyframes": {"type": "integer", "description": "In the estimator's window"}, )"
    R"("inliers": {"type": "integer"}, )"
    R"("dropped": {"type": "integer", "description": "Frames the live policy dropped since the start"}, )"
    R"("damaged": {"type": "integer", "description": "Damaged frames skipped since the start"}, )"
    R"("view_dropped": {"type": "integer", "description": "Frame updates the telemetry did not keep up with since the start"}}})";

#undef VOCA_SCHEMA_TIME
#undef VOCA_SCHEMA_VECTOR3
#undef VOCA_SCHEMA_QUATERNION
#undef VOCA_SCHEMA_POSE
#undef VOCA_SCHEMA_COLOR
#undef VOCA_SCHEMA_POINT2

constexpr std::array<Schema, 7> kSchemas = {{
    {SchemaId::kCompressedImage, "foxglove.CompressedImage", kCompressedImage},
    {SchemaId::kImageAnnotations, "foxglove.ImageAnnotations", kImageAnnotations},
    {SchemaId::kPoseInFrame, "foxglove.PoseInFrame", kPoseInFrame},
    {SchemaId::kPosesInFrame, "foxglove.PosesInFrame", kPosesInFrame},
    {SchemaId::kFrameTransform, "foxglove.FrameTransform", kFrameTransform},
    {SchemaId::kPointCloud, "foxglove.PointCloud", kPointCloud},
    {SchemaId::kFrameStats, "voca.FrameStats", kFrameStats},
}};

}  // namespace

const Schema& schema(SchemaId id) { return kSchemas[static_cast<std::size_t>(id)]; }

std::span<const Schema> allSchemas() { return kSchemas; }

}  // namespace voca::foxglove

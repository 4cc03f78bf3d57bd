#pragma once
// The JSON Schemas of the messages VOCA-RT publishes for Foxglove and Lichtblick (and records to MCAP):
// the standard foxglove.* schemas that their panels draw without configuration, and voca.FrameStats.
// Channels carry JSON (message encoding "json") described by these schemas (schema encoding
// "jsonschema"); byte fields are base64 strings marked with "contentEncoding": "base64", which is how
// the JSON readers know to decode them.

#include <span>
#include <string_view>

namespace voca::foxglove {

inline constexpr std::string_view kJsonEncoding = "json";
inline constexpr std::string_view kJsonSchemaEncoding = "jsonschema";

enum class SchemaId {
  kCompressedImage,
  kImageAnnotations,
  kPoseInFrame,
  kPosesInFrame,
  kFrameTransform,
  kPointCloud,
  kFrameStats,
};

struct Schema {
  SchemaId id;
  std::string_view name;  // e.g. "foxglove.PoseInFrame": what the viewers pick a panel by
  std::string_view text;  // the JSON Schema document
};

const Schema& schema(SchemaId id);
std::span<const Schema> allSchemas();

}  // namespace voca::foxglove

#pragma once
// ROS 2's names as a node without ROS has to apply them itself: topic names (rcl's rules, resolved
// in the root namespace), their DDS topic names, tf frame ids, and the domain from ROS_DOMAIN_ID.

#include <cstdint>
#include <string>
#include <string_view>

namespace voca::ros2 {

// The largest domain id whose DDS ports (7400 + 250 * domain + offsets) stay below 65536.
inline constexpr std::uint32_t kMaxDomainId = 232;

// A ROS topic name resolved as a node in the root namespace resolves it: "odom" and "/odom" both give
// "/odom". Throws InputError naming `option` and what is wrong: empty, characters other than letters,
// digits, '_' and '/', a part starting with a digit, "//", a trailing '/', more than 247 characters
// (ROS's limit), or '~' and '{...}' (private names and substitutions need a node name; voca has none).
std::string fullyQualifiedTopicName(std::string_view name, std::string_view option);

// The DDS topic ROS 2 uses for a fully qualified topic name: "/odom" -> "rt/odom".
std::string ddsTopicName(std::string_view fully_qualified_name);

// A tf frame id: non-empty, letters, digits, '_' and '/' (for a robot's prefix: "robot1/odom"), not
// starting with '/' (tf2 rejects those). Throws InputError naming `option`.
void checkFrameId(std::string_view frame_id, std::string_view option);

// The value of ROS_DOMAIN_ID: nullptr (unset) or empty is domain 0, as in ROS 2; otherwise a decimal
// integer 0..kMaxDomainId. Throws InputError quoting the value.
std::uint32_t parseDomainId(const char* value);

// parseDomainId of the environment's ROS_DOMAIN_ID.
std::uint32_t domainIdFromEnvironment();

}  // namespace voca::ros2

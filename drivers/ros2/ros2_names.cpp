#include "drivers/ros2/ros2_names.h"

#include <fmt/core.h>

#include <cstdlib>

#include "voca/core/error.h"

namespace voca::ros2 {

namespace {

// rmw's limit on a fully qualified topic name: 255 (RTPS) less room for the "rt" prefix and more.
constexpr std::size_t kMaxTopicNameLength = 247;

bool isAsciiAlpha(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool isAsciiDigit(char c) { return c >= '0' && c <= '9'; }
bool isNameCharacter(char c) { return isAsciiAlpha(c) || isAsciiDigit(c) || c == '_' || c == '/'; }

// Letters, digits, '_' and '/', no empty part, no part starting with a digit. `name` is checked as
// written, so positions in messages are the user's; the leading '/' of an absolute name is skipped.
void checkNameParts(std::string_view name, std::string_view option, std::string_view what) {
  const std::size_t first = name.front() == '/' ? 1 : 0;
  if (first == name.size()) throw InputError(fmt::format("{} \"{}\": the root alone names no {}", option, name, what));
  for (std::size_t i = first; i < name.size(); ++i) {
    const char c = name[i];
    if (!isNameCharacter(c)) {
      throw InputError(
          fmt::format("{} \"{}\": character {} ('{}') is not allowed in a ROS {} (letters, digits, '_' "
                      "and '/' only)",
                      option, name, i + 1, c, what));
    }
    const bool part_start = i == first || name[i - 1] == '/';
    if (part_start && c == '/') {
      throw InputError(fmt::format("{} \"{}\": an empty part (\"//\" or a stray '/') in a ROS {}", option, name, what));
    }
    if (part_start && isAsciiDigit(c)) {
      throw InputError(fmt::format("{} \"{}\": a part of a ROS {} must not start with a digit (character {})", option,
                                   name, what, i + 1));
    }
  }
  if (name.back() == '/')
    throw InputError(fmt::format("{} \"{}\": a ROS {} must not end with '/'", option, name, what));
}

}  // namespace

std::string fullyQualifiedTopicName(std::string_view name, std::string_view option) {
  if (name.empty()) throw InputError(fmt::format("{}: an empty topic name; give one such as /odom", option));
  if (name.front() == '~') {
    throw InputError(
        fmt::format("{} \"{}\": '~' names a node's private topic, and voca publishes without a ROS node; "
                    "give the full name (/robot1/odom)",
                    option, name));
  }
  if (name.find_first_of("{}") != std::string_view::npos) {
    throw InputError(fmt::format(
        "{} \"{}\": substitutions ({{node}}, {{ns}}) need a ROS node; give the name they stand for", option, name));
  }
  checkNameParts(name, option, "topic name");
  std::string full;
  if (name.front() != '/') full.push_back('/');
  full.append(name);
  if (full.size() > kMaxTopicNameLength) {
    throw InputError(fmt::format("{}: \"{}\" has {} characters; ROS 2 allows {} in a topic name", option, full,
                                 full.size(), kMaxTopicNameLength));
  }
  return full;
}

std::string ddsTopicName(std::string_view fully_qualified_name) { return "rt" + std::string(fully_qualified_name); }

void checkFrameId(std::string_view frame_id, std::string_view option) {
  if (frame_id.empty()) throw InputError(fmt::format("{}: an empty frame id; give one such as odom", option));
  if (frame_id.front() == '/') {
    std::string_view relative = frame_id;
    while (!relative.empty() && relative.front() == '/') relative.remove_prefix(1);
    throw InputError(
        fmt::format("{} \"{}\": tf2 frame ids do not start with '/' (write \"{}\")", option, frame_id, relative));
  }
  checkNameParts(frame_id, option, "frame id");
}

std::uint32_t parseDomainId(const char* value) {
  if (value == nullptr || *value == '\0') return 0;
  const std::string_view text(value);
  std::uint32_t domain = 0;
  bool valid = text.size() <= 3;
  for (const char c : text) {
    if (!isAsciiDigit(c)) valid = false;
    if (valid) domain = domain * 10 + static_cast<std::uint32_t>(c - '0');
  }
  if (!valid || domain > kMaxDomainId) {
    throw InputError(
        fmt::format("ROS_DOMAIN_ID=\"{}\": expected a ROS 2 domain id, an integer from 0 to {} (unset or "
                    "empty means 0)",
                    text, kMaxDomainId));
  }
  return domain;
}

std::uint32_t domainIdFromEnvironment() { return parseDomainId(std::getenv("ROS_DOMAIN_ID")); }

}  // namespace voca::ros2

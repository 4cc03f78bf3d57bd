#pragma once
// The configurations shipped in configs/, compiled into the library so that a run can name one
// (`--config euroc`) from anywhere.

#include <span>
#include <string_view>

namespace voca {

struct BuiltinConfig {
  std::string_view name;  // file stem without "_vo": "euroc", "kitti", "tumvi"
  std::string_view json;
};

std::span<const BuiltinConfig> builtinConfigs();

}  // namespace voca

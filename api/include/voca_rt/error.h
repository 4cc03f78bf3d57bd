#pragma once
// The one exception type of the library. Its message is the one the `voca` command line prints after
// "error: " for the same problem (naming the file, field, option or frame and what was expected).

#include <stdexcept>
#include <string>

#include "voca_rt/export.h"

namespace voca_rt {

class VOCA_RT_API Error : public std::runtime_error {
 public:
  enum class Kind {
    kInput,    // unusable input: a file, an option, a frame that does not fit (the CLI exits 1)
    kRuntime,  // a device, codec or the operating system failed
  };
  Error(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

}  // namespace voca_rt

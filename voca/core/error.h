#pragma once
// Errors that reach the user: bad files, options, configs, streams and devices.

#include <stdexcept>
#include <string>

namespace voca {

// Thrown when input from a user or a file is unusable. The message names the file, line or
// field and says what was expected; the command line turns it into "error: ..." and exit 1.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Thrown when a device, codec or the operating system fails at run time.
class RuntimeFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace voca

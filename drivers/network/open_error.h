#pragma once
// Why libavformat could not open a network URL, in its own words. Its error code alone is often
// misleading ("Input/output error" for a host name that does not resolve, "Inappropriate ioctl for
// device" for a UDP port another program holds); the real reason goes to its log.

#include <string>

namespace voca::network {

// While one lives, libav's error-level log lines on this thread are kept instead of printed (other
// lines and other threads are printed as before). Open a URL inside its scope, then ask reason().
class OpenErrorCapture {
 public:
  OpenErrorCapture();
  ~OpenErrorCapture();
  OpenErrorCapture(const OpenErrorCapture&) = delete;
  OpenErrorCapture& operator=(const OpenErrorCapture&) = delete;

  // The error lines logged since construction, joined by "; " ("bind failed: Address already in
  // use"), followed by the code's own text when it adds something; the code's text alone when
  // nothing was logged.
  std::string reason(int av_error_code) const;
};

}  // namespace voca::network

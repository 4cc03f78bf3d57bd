#include "drivers/network/open_error.h"

#include <cstdarg>
#include <cstdio>
#include <mutex>

#include "drivers/ffmpeg/av_objects.h"

extern "C" {
#include <libavutil/error.h>
#include <libavutil/log.h>
}

namespace voca::network {

namespace {

// This thread's capture: active while an OpenErrorCapture lives on it.
struct ThreadCapture {
  int depth = 0;
  std::string lines;
};
thread_local ThreadCapture t_capture;

void captureOrPrint(void* context, int level, const char* format, va_list args) {
  ThreadCapture& capture = t_capture;
  if (capture.depth > 0 && level <= AV_LOG_ERROR && level <= av_log_get_level()) {
    char line[512];
    va_list copy;
    va_copy(copy, args);
    std::vsnprintf(line, sizeof(line), format, copy);
    va_end(copy);
    std::string text(line);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    if (!text.empty()) capture.lines += (capture.lines.empty() ? "" : "; ") + text;
    return;
  }
  av_log_default_callback(context, level, format, args);
}

}  // namespace

OpenErrorCapture::OpenErrorCapture() {
  // Installed once for the process; it prints like the default callback outside a capture.
  static std::once_flag installed;
  std::call_once(installed, [] { av_log_set_callback(captureOrPrint); });
  if (t_capture.depth++ == 0) t_capture.lines.clear();
}

OpenErrorCapture::~OpenErrorCapture() { --t_capture.depth; }

std::string OpenErrorCapture::reason(int av_error_code) const {
  const std::string code = ffmpeg::avErrorText(av_error_code);
  const std::string& logged = t_capture.lines;
  if (logged.empty()) return code;
  // The code's text adds nothing the log said, and for these failures it is usually a misleading
  // errno; it stays only when it is not one of the generic ones.
  if (av_error_code == AVERROR(EIO) || av_error_code == AVERROR(ENOTTY) || logged.find(code) != std::string::npos) {
    return logged;
  }
  return logged + " (" + code + ")";
}

}  // namespace voca::network

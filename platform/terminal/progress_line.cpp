#include "platform/terminal/progress_line.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>

namespace voca::platform {

ProgressLine::ProgressLine(std::FILE* stream, Mode mode, std::int64_t log_interval_ns,
                           std::function<std::int64_t()> now_ns)
    : stream_(stream),
      terminal_(mode == Mode::kTerminal || (mode == Mode::kAuto && isatty(fileno(stream)) == 1)),
      log_interval_ns_(log_interval_ns),
      now_ns_(std::move(now_ns)) {}

ProgressLine::~ProgressLine() { end(); }

void ProgressLine::update(std::string_view text) {
  text_.clear();
  text_.append(text);
  publish();
}

void ProgressLine::publish() {
  const std::string_view text(text_.data(), text_.size());
  if (terminal_) {
    write("\r");
    write(text);
    // The previous text may have been longer: blank what would be left of it.
    if (open_ && shown_ > text.size()) writeSpaces(shown_ - text.size());
    shown_ = text.size();
    open_ = true;
  } else {
    const std::int64_t t = now();
    if (open_ && t - printed_ns_ < log_interval_ns_) return;  // held back; end() prints the last one
    write(text);
    write("\n");
    printed_.clear();
    printed_.append(text);
    printed_ns_ = t;
    open_ = true;
  }
  std::fflush(stream_);
}

void ProgressLine::message(std::string_view line) {
  if (terminal_ && open_) {
    write("\n");
    open_ = false;
  }
  write(line);
  write("\n");
  std::fflush(stream_);
}

void ProgressLine::end() {
  if (!open_) return;
  if (terminal_) {
    write("\n");
  } else if (std::string_view(text_.data(), text_.size()) != std::string_view(printed_.data(), printed_.size())) {
    write(std::string_view(text_.data(), text_.size()));
    write("\n");
  }
  std::fflush(stream_);
  open_ = false;
}

void ProgressLine::clear() {
  if (!terminal_ || !open_) {
    end();
    return;
  }
  write("\r");
  writeSpaces(shown_);
  write("\r");
  std::fflush(stream_);
  open_ = false;
}

void ProgressLine::write(std::string_view text) { std::fwrite(text.data(), 1, text.size(), stream_); }

void ProgressLine::writeSpaces(std::size_t count) {
  static constexpr std::string_view kSpaces = "                                                                ";
  while (count > 0) {
    const std::size_t n = std::min(count, kSpaces.size());
    write(kSpaces.substr(0, n));
    count -= n;
  }
}

std::int64_t ProgressLine::now() const {
  if (now_ns_) return now_ns_();
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace voca::platform

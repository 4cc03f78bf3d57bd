#pragma once
// The one progress line of a long command on stderr ("frame 120/800 ..."). On a terminal it is
// rewritten in place; in a log file or a pipe each update would otherwise pile up on one endless
// line, so there it becomes whole lines, throttled to the first, one every few seconds and the last.

#include <fmt/format.h>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <iterator>
#include <string_view>
#include <utility>

namespace voca::platform {

// Owns the line from the first update() to end(). Anything else printed on the same stream while
// the line is open goes through message(), which puts it on a line of its own. Not thread-safe:
// one thread updates it. end() writes with fwrite and never throws: it runs in the destructor, also
// while an exception unwinds, so an error printed after that starts a line of its own.
class ProgressLine {
 public:
  enum class Mode {
    kAuto,      // terminal when the stream is a tty
    kTerminal,  // '\r' rewrites one line
    kLog,       // whole lines ending in '\n', throttled
  };
  // A log gets an update at most this often: a 10-minute run leaves about 120 progress lines.
  static constexpr std::int64_t kLogIntervalNs = 5'000'000'000;

  // now_ns: the clock the log throttle reads (default: steady clock); injectable for tests.
  explicit ProgressLine(std::FILE* stream = stderr, Mode mode = Mode::kAuto,
                        std::int64_t log_interval_ns = kLogIntervalNs, std::function<std::int64_t()> now_ns = {});
  ~ProgressLine();
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  bool onTerminal() const { return terminal_; }

  // The latest state of the work. Formatting into the line's own buffer allocates nothing once it
  // has grown to the longest text.
  void update(std::string_view text);
  template <typename... Args>
  void update(fmt::format_string<Args...> format, Args&&... args) {
    text_.clear();
    fmt::format_to(std::back_inserter(text_), format, std::forward<Args>(args)...);
    publish();
  }

  // Prints line (without its '\n') on a line of its own: a warning or a per-frame note between
  // updates. The progress goes on with the next update, below it.
  void message(std::string_view line);
  template <typename... Args>
  void message(fmt::format_string<Args...> format, Args&&... args) {
    fmt::memory_buffer line;  // on the stack up to 500 characters
    fmt::format_to(std::back_inserter(line), format, std::forward<Args>(args)...);
    message(std::string_view(line.data(), line.size()));
  }

  // Finishes the line: on a terminal a '\n' after the text shown; in a log the latest text when the
  // throttle held it back. The next update starts a new line (and, in a log, is printed at once).
  void end();

  // end() for a transient line, such as a repeat counter that a table row replaces: on a terminal
  // the text is wiped and the cursor left at the start of the empty line.
  void clear();

 private:
  void publish();
  void write(std::string_view text);
  void writeSpaces(std::size_t count);
  std::int64_t now() const;

  std::FILE* stream_;
  bool terminal_;
  std::int64_t log_interval_ns_;
  std::function<std::int64_t()> now_ns_;
  fmt::memory_buffer text_;      // the latest update
  fmt::memory_buffer printed_;   // log: the last update printed
  bool open_ = false;            // terminal: text on screen, cursor after it; log: an update since end()
  std::size_t shown_ = 0;        // terminal: characters of the text on screen
  std::int64_t printed_ns_ = 0;  // log: when printed_ was printed
};

}  // namespace voca::platform

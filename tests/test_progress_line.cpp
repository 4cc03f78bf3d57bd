// The shared progress line (platform/terminal) in both modes, on a tmpfile() instead of a tty, with
// a hand-driven clock so the log throttle is exact.

#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "platform/terminal/progress_line.h"

namespace {

using voca::platform::ProgressLine;

// What was written to the stream so far.
std::string contents(std::FILE* file) {
  std::fflush(file);
  std::rewind(file);
  std::string text;
  for (int c; (c = std::fgetc(file)) != EOF;) text.push_back(static_cast<char>(c));
  return text;
}

// A temporary file closed at the end of the test.
struct TempStream {
  std::FILE* file = std::tmpfile();
  ~TempStream() {
    if (file != nullptr) std::fclose(file);
  }
};

constexpr std::int64_t kSecond = 1'000'000'000;

}  // namespace

TEST_CASE("on a terminal the line is rewritten in place and ended with a newline") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  {
    ProgressLine line(out.file, ProgressLine::Mode::kTerminal);
    CHECK(line.onTerminal());
    line.update("frame 1/10");
    line.update("frame {}/{}", 10, 10);
  }  // the destructor ends the line
  CHECK(contents(out.file) == "\rframe 1/10\rframe 10/10\n");
}

TEST_CASE("on a terminal a shorter text blanks what the longer one left") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  ProgressLine line(out.file, ProgressLine::Mode::kTerminal);
  line.update("frame 100/100 long");
  line.update("done");
  line.end();
  line.end();  // a second end() prints nothing more
  CHECK(contents(out.file) == "\rframe 100/100 long\rdone              \n");
}

TEST_CASE("on a terminal a message starts a line of its own and the progress goes on below it") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  ProgressLine line(out.file, ProgressLine::Mode::kTerminal);
  line.message("warning: before any progress");
  line.update("frame 20/60");
  line.message("frame {}: {} ({})", 25, "lost", "too few inliers");
  line.update("frame 40/60");
  line.end();
  CHECK(contents(out.file) ==
        "warning: before any progress\n\rframe 20/60\nframe 25: lost (too few inliers)\n\rframe 40/60\n");
}

TEST_CASE("clear() wipes a transient line on a terminal and ends it in a log") {
  TempStream terminal, log;
  REQUIRE(terminal.file != nullptr);
  REQUIRE(log.file != nullptr);
  ProgressLine on_terminal(terminal.file, ProgressLine::Mode::kTerminal);
  ProgressLine in_log(log.file, ProgressLine::Mode::kLog, 100 * kSecond, [] { return std::int64_t{0}; });
  for (ProgressLine* line : {&on_terminal, &in_log}) {
    line->update("repeat 1/2");
    line->update("repeat 2/2");
    line->clear();
  }
  CHECK(contents(terminal.file) == "\rrepeat 1/2\rrepeat 2/2\r          \r");
  CHECK(contents(log.file) == "repeat 1/2\nrepeat 2/2\n");
}

TEST_CASE("in a log every update is a whole line, throttled, with the last state always written") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  std::int64_t now_ns = 0;
  ProgressLine line(out.file, ProgressLine::Mode::kLog, 5 * kSecond, [&] { return now_ns; });
  CHECK(!line.onTerminal());
  // One update a second for 12 s: the first, then one whenever 5 s have passed since the last printed.
  for (int k = 1; k <= 12; ++k) {
    line.update("frame {}/12", k);
    now_ns += kSecond;
  }
  line.end();
  CHECK(contents(out.file) == "frame 1/12\nframe 6/12\nframe 11/12\nframe 12/12\n");
}

TEST_CASE("in a log the final state is not repeated when it was the last line printed") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  std::int64_t now_ns = 0;
  {
    ProgressLine line(out.file, ProgressLine::Mode::kLog, 5 * kSecond, [&] { return now_ns; });
    line.update("pass 1: frame 1/2");
    now_ns += 6 * kSecond;
    line.update("pass 1: frame 2/2");
    line.end();
    // After end() the next update is a new line's first, printed at once however soon it comes.
    line.update("pass 2: frame 1/2");
    line.update("pass 2: frame 2/2");
  }  // the destructor writes the held-back last state
  CHECK(contents(out.file) == "pass 1: frame 1/2\npass 1: frame 2/2\npass 2: frame 1/2\npass 2: frame 2/2\n");
}

TEST_CASE("in a log an interval of 0 writes every update, and a message is a line of its own") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  ProgressLine line(out.file, ProgressLine::Mode::kLog, 0, [] { return std::int64_t{0}; });
  line.update("frame 20/60");
  line.message("frame 25: lost (too few inliers)");
  line.update("frame 40/60");
  line.end();
  CHECK(contents(out.file) == "frame 20/60\nframe 25: lost (too few inliers)\nframe 40/60\n");
}

TEST_CASE("in a log a message between held-back updates does not lose the final state") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  ProgressLine line(out.file, ProgressLine::Mode::kLog, 100 * kSecond, [] { return std::int64_t{0}; });
  line.update("frame 20/60");
  line.update("frame 40/60");
  line.message("warning: something");
  line.update("frame 60/60");
  line.end();
  CHECK(contents(out.file) == "frame 20/60\nwarning: something\nframe 60/60\n");
}

TEST_CASE("the automatic mode writes a file as a log") {
  TempStream out;
  REQUIRE(out.file != nullptr);
  ProgressLine line(out.file);
  CHECK(!line.onTerminal());
  line.update("frame 1/2");
  line.end();
  const std::string text = contents(out.file);
  CHECK(text == "frame 1/2\n");
  CHECK(text.find('\r') == std::string::npos);
}

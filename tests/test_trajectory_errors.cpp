#include <doctest/doctest.h>

#include <fstream>
#include <string>

#include "formats/trajectory/trajectory_io.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

// Malformed trajectory files must give an InputError naming the file and line, never a crash.

namespace {

// Loads `text` as a trajectory file and returns the error message ("" if it loaded).
std::string loadError(const voca::test::ScratchDir& dir, const std::string& name, const std::string& text,
                      std::optional<voca::TrajectoryFormat> format = {}, const std::string& times = "") {
  const auto path = dir / name;
  {
    std::ofstream out(path);
    out << text;
  }
  std::filesystem::path times_path;
  if (!times.empty()) {
    times_path = dir / "times.txt";
    std::ofstream out(times_path);
    out << times;
  }
  try {
    voca::loadTrajectory(path, format, times_path);
  } catch (const voca::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("malformed trajectory files name the file and line") {
  const voca::test::ScratchDir dir("trajectory-errors");
  const auto contains = [](const std::string& message, const std::string& part) {
    INFO(message);
    CHECK(message.find(part) != std::string::npos);
  };

  contains(loadError(dir, "short.txt", "0 1 2 3 0 0 0 1\n1 1 2 3 0 0 1\n"), "short.txt:2");
  // A device is refused before reading: /dev/zero has no line end, so its one line grew without bound.
  CHECK(voca::test::inputErrorOf([] { voca::loadTrajectory("/dev/zero"); }) ==
        "trajectory file /dev/zero is a device, not a file");
  contains(loadError(dir, "short.txt", "0 1 2 3 0 0 0 1\n1 1 2 3 0 0 1\n"), "found 7");
  contains(loadError(dir, "nan.txt", "# c\n0 1 2 nan 0 0 0 1\n"), "nan.txt:2");
  contains(loadError(dir, "word.txt", "0 1 2 x3 0 0 0 1\n"), "tz 'x3'");
  contains(loadError(dir, "time.txt", "1.2.3 1 2 3 0 0 0 1\n"), "timestamp '1.2.3'");
  contains(loadError(dir, "zeroq.txt", "0 1 2 3 0 0 0 0\n"), "zero length");
  contains(loadError(dir, "order.txt", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n"), "order.txt:2");
  contains(loadError(dir, "order.txt", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n"), "before the previous");
  // A repeated timestamp is kept (real estimates have them), only going back is an error.
  CHECK(loadError(dir, "repeat.txt", "1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n").empty());
  contains(loadError(dir, "empty.txt", "# nothing\n\n"), "no poses");
  contains(loadError(dir, "odd.txt", "1 2 3 4 5\n"), "cannot tell the trajectory format");
  contains(loadError(dir, "missing/none.txt", ""), "cannot open");

  contains(loadError(dir, "gt.csv", "#h\n5,1,2,3,1,0,0,0\n6,1,2,3\n"), "gt.csv:3");
  contains(loadError(dir, "gt.csv", "#h\n5.5,1,2,3,1,0,0,0\n"), "integer number of nanoseconds");
  contains(loadError(dir, "gt.csv", "#h\n5,1,,3,1,0,0,0\n"), "py ''");

  const std::string kitti_row = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  contains(loadError(dir, "k.txt", kitti_row + "1 0 0 0 0 1 0 0 0 0 1\n", voca::TrajectoryFormat::kKitti), "k.txt:2");
  contains(loadError(dir, "k.txt", "2 0 0 0 0 1 0 0 0 0 1 0\n"), "not a rotation");
  contains(loadError(dir, "k.txt", kitti_row + kitti_row, {}, "0.0\n"), "1 times but");
  contains(loadError(dir, "k.txt", kitti_row + kitti_row, {}, "1.0\n0.5\n"), "times.txt:2");
  contains(loadError(dir, "t.txt", "0 1 2 3 0 0 0 1\n", {}, "0\n"), "only KITTI");
  // Forcing a format that does not fit is reported the same way.
  contains(loadError(dir, "forced.txt", kitti_row, voca::TrajectoryFormat::kTum), "forced.txt:1");
  CHECK(loadError(dir, "ok.txt", kitti_row + kitti_row).empty());
}

// Trajectory files: TUM, EuRoC csv and KITTI (3x4 rows), each format forced and auto-detected.
#include "formats/trajectory/trajectory_io.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("traj.txt", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadTrajectory(path); });
  for (const auto format :
       {voca::TrajectoryFormat::kTum, voca::TrajectoryFormat::kEuroc, voca::TrajectoryFormat::kKitti}) {
    voca::fuzz::expectOnlyInputErrors([&] { voca::loadTrajectory(path, format); });
  }
  return 0;
}

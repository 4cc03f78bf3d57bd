// Trajectory files: TUM, EuRoC csv and KITTI (3x4 rows), each format forced and auto-detected.
#include "tests/fuzz/fuzz_support.h"
#include "voca/trajectory/trajectory.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = voca::fuzz::writeInput("traj.txt", data, size);
  voca::fuzz::expectOnlyInputErrors([&] { voca::loadTrajectory(path); });
  for (const auto format :
       {voca::TrajectoryFormat::kTum, voca::TrajectoryFormat::kEuroc, voca::TrajectoryFormat::kKitti}) {
    voca::fuzz::expectOnlyInputErrors([&] { voca::loadTrajectory(path, format); });
  }
  return 0;
}

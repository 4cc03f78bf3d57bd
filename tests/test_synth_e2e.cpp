// End-to-end checks of `voca synth`: runs the command and reads its output with the project's readers.

#include <fstream>
#include <iterator>
#include <string>

#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/synth/synth_runner.h"
#include "tests/test_support.h"
#include "voca/synth/rigs.h"

namespace fs = std::filesystem;

namespace {

using voca::test::runVoca;

std::string readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

}  // namespace

TEST_CASE("voca synth writes a EuRoC folder with ground truth and calibration that the readers accept") {
  voca::test::ScratchDir scratch("synth-e2e");
  const fs::path out = scratch / "seq";
  REQUIRE(runVoca("synth --out " + out.string() + " --seconds 0.5 --seed 3 --motion aggressive") == 0);

  const voca::Dataset dataset = voca::openDataset(out);
  CHECK(dataset.layout == voca::DatasetLayout::kEuroc);
  REQUIRE(dataset.frames.size() == 10);  // 0.5 s at 20 Hz
  CHECK(dataset.warnings.empty());
  REQUIRE(dataset.ground_truth.has_value());
  REQUIRE(dataset.calibration.has_value());

  const voca::GrayImage left = voca::readPngGray(dataset.frames[0].left);
  CHECK(left.width() == 752);
  CHECK(left.height() == 480);

  const voca::StereoRig rig = voca::loadCalibration(out / "calib.json");
  const voca::StereoRig builtin = voca::synth::eurocRig();
  REQUIRE(rig.cameras.size() == 2);
  for (int c = 0; c < 2; ++c) {
    CHECK(rig.cameras[c].camera.modelName() == "pinhole-radtan8");
    CHECK(rig.cameras[c].width == 752);
    // The JSON stores the values with full precision.
    CHECK((rig.cameras[c].T_body_cam.matrix() - builtin.cameras[c].T_body_cam.matrix()).norm() < 1e-9);
  }

  const voca::Trajectory gt = voca::loadTrajectory(*dataset.ground_truth);
  REQUIRE(gt.poses.size() == dataset.frames.size());
  for (std::size_t i = 0; i < gt.poses.size(); ++i) CHECK(gt.poses[i].t_ns == dataset.frames[i].t_ns);
  // Consecutive ground-truth poses 50 ms apart: the drone-like preset moves, but continuously.
  for (std::size_t i = 1; i < gt.poses.size(); ++i) {
    const double step = (gt.poses[i].T_world_body.translation() - gt.poses[i - 1].T_world_body.translation()).norm();
    CHECK(step > 0.0);
    CHECK(step < 0.25);  // 5 m/s at most
  }

  SUBCASE("the same seed gives the same bytes, another seed other noise") {
    const fs::path again = scratch / "again";
    const fs::path other = scratch / "other";
    REQUIRE(runVoca("synth --out " + again.string() + " --seconds 0.5 --seed 3 --motion aggressive") == 0);
    REQUIRE(runVoca("synth --out " + other.string() + " --seconds 0.5 --seed 4 --motion aggressive") == 0);
    const fs::path gt_rel = fs::path("mav0") / "state_groundtruth_estimate0" / "data.csv";
    CHECK(readBytes(out / gt_rel) == readBytes(again / gt_rel));
    CHECK(readBytes(out / gt_rel) == readBytes(other / gt_rel));  // the seed only drives the noise
    for (const voca::StereoFrameRef& frame : dataset.frames) {
      const fs::path rel = fs::relative(frame.right, out);
      CHECK(readBytes(frame.right) == readBytes(again / rel));
      CHECK(readBytes(frame.right) != readBytes(other / rel));
    }
  }

  SUBCASE("a trajectory file is followed, resampled and re-centred") {
    // The ground truth just written, moved far away and slowed down to 10 Hz timestamps spacing.
    voca::Trajectory shifted = gt;
    for (voca::TimedPose& pose : shifted.poses) pose.T_world_body.translation() += Eigen::Vector3d(100.0, -40.0, 3.0);
    const fs::path file = scratch / "shifted.txt";
    voca::saveTrajectory(shifted, file, voca::TrajectoryFormat::kTum);
    const fs::path followed = scratch / "followed";
    REQUIRE(runVoca("synth --out " + followed.string() + " --trajectory " + file.string() + " --rate 40") == 0);
    const voca::Trajectory result =
        voca::loadTrajectory(followed / "mav0" / "state_groundtruth_estimate0" / "data.csv");
    // 0.45 s of trajectory at 40 Hz: 19 frames, every one at a file time or between two.
    REQUIRE(result.poses.size() == 19);
    CHECK(result.poses.front().t_ns == shifted.poses.front().t_ns);
    const Eigen::Vector3d offset =
        result.poses.front().T_world_body.translation() - shifted.poses.front().T_world_body.translation();
    for (std::size_t i = 0; i < result.poses.size(); i += 2) {
      // Even frames fall on the file's own timestamps: same rotation, same translation up to the offset.
      const voca::SE3d& expected = shifted.poses[i / 2].T_world_body;
      CHECK((result.poses[i].T_world_body.translation() - expected.translation() - offset).norm() < 1e-6);
      CHECK((result.poses[i].T_world_body.so3().inverse() * expected.so3()).log().norm() < 1e-6);
    }
    // Re-centred: the camera ends up in the room (the default room is centred on the origin).
    CHECK(result.poses.front().T_world_body.translation().head<2>().norm() < 5.0);

    // --start skips into the file: 0.2 s later, 11 frames left, the first at the file's fifth pose.
    const fs::path later = scratch / "later";
    REQUIRE(runVoca("synth --out " + later.string() + " --trajectory " + file.string() + " --rate 40 --start 0.2") ==
            0);
    const voca::Trajectory skipped = voca::loadTrajectory(later / "mav0" / "state_groundtruth_estimate0" / "data.csv");
    REQUIRE(skipped.poses.size() == 11);
    CHECK(skipped.poses.front().t_ns == shifted.poses[4].t_ns);
    // Asked for more than the file holds: all it holds, and a warning that says so.
    const voca::test::CommandOutput longer = voca::test::runVocaOutput(
        "synth --out " + (scratch / "longer").string() + " --trajectory " + file.string() + " --rate 40 --seconds 5");
    INFO(longer.text);
    CHECK(longer.exit_code == 0);
    CHECK(longer.text.find("warning: --seconds 5: " + file.string() +
                           " from --start 0 s holds only 19 frames at 40 Hz; wrote those") != std::string::npos);
    CHECK(runVoca("synth --out " + (scratch / "late").string() + " --trajectory " + file.string() + " --start 9") ==
          1 << 8);
  }
}

TEST_CASE("voca synth renders the TUM-VI fisheye rig") {
  voca::test::ScratchDir scratch("synth-e2e-tumvi");
  const fs::path out = scratch / "seq";
  REQUIRE(runVoca("synth --out " + out.string() + " --camera tumvi --motion fast-rotation --seconds 0.15") == 0);
  const voca::Dataset dataset = voca::openDataset(out);
  REQUIRE(dataset.frames.size() == 3);
  const voca::GrayImage image = voca::readPngGray(dataset.frames[2].left);
  CHECK(image.width() == 512);
  CHECK(image.height() == 512);
  const voca::StereoRig rig = voca::loadCalibration(*dataset.calibration);
  CHECK(rig.cameras[0].camera.modelName() == "kb4");
  // A textured scene everywhere: no large flat areas (the standard deviation of 16x16 blocks).
  int flat_blocks = 0, blocks = 0;
  for (int by = 0; by + 16 <= image.height(); by += 16) {
    for (int bx = 0; bx + 16 <= image.width(); bx += 16) {
      double sum = 0.0, sum2 = 0.0;
      for (int y = by; y < by + 16; ++y) {
        for (int x = bx; x < bx + 16; ++x) {
          sum += image(x, y);
          sum2 += static_cast<double>(image(x, y)) * image(x, y);
        }
      }
      const double mean = sum / 256.0;
      flat_blocks += (sum2 / 256.0 - mean * mean) < 9.0;  // below 3 gray levels: noise only
      ++blocks;
    }
  }
  CHECK(flat_blocks < blocks / 20);
}

TEST_CASE("voca synth renders exposure blur and dark scenes: same poses, less contrast and detail") {
  voca::test::ScratchDir scratch("synth-e2e-blur");
  const std::string common = " --motion aggressive --seconds 0.15 --noise-sigma 0";  // gradients of the scene only
  REQUIRE(runVoca("synth --out " + (scratch / "sharp").string() + common) == 0);
  REQUIRE(runVoca("synth --out " + (scratch / "blur").string() + common + " --exposure 15 --gain 0.4") == 0);
  const voca::Dataset sharp = voca::openDataset(scratch / "sharp");
  const voca::Dataset blur = voca::openDataset(scratch / "blur");
  REQUIRE(sharp.frames.size() == 3);
  REQUIRE(blur.frames.size() == 3);
  // Mean brightness and mean horizontal gradient: the gain scales both; blur removes detail on top.
  const auto measure = [](const fs::path& png) {
    const voca::GrayImage image = voca::readPngGray(png);
    double sum = 0.0, gradient = 0.0;
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x + 1 < image.width(); ++x) {
        sum += image(x, y);
        gradient += std::abs(static_cast<int>(image(x + 1, y)) - static_cast<int>(image(x, y)));
      }
    }
    const double n = static_cast<double>(image.height()) * (image.width() - 1);
    return std::pair{sum / n, gradient / n};
  };
  const auto [sharp_mean, sharp_gradient] = measure(sharp.frames[2].left);
  const auto [blur_mean, blur_gradient] = measure(blur.frames[2].left);
  CHECK(blur_mean == doctest::Approx(0.4 * sharp_mean).epsilon(0.05));
  // Gain alone would keep 0.4 of the gradient; the streaks must take detail away on top of that.
  CHECK(blur_gradient < 0.4 * sharp_gradient);
  // Ground truth is the same motion, sampled at the same timestamps.
  CHECK(fs::file_size(scratch / "sharp" / "mav0" / "state_groundtruth_estimate0" / "data.csv") ==
        fs::file_size(scratch / "blur" / "mav0" / "state_groundtruth_estimate0" / "data.csv"));
}

TEST_CASE("voca synth rejects bad options with a clear error") {
  voca::test::ScratchDir scratch("synth-e2e-bad");
  CHECK(runVoca("synth --out " + (scratch / "a").string() + " --motion sideways") == 1 << 8);
  CHECK(runVoca("synth --out " + (scratch / "b").string() + " --camera /nonexistent/calib.json") == 1 << 8);
  CHECK(runVoca("synth --out " + (scratch / "c").string() + " --rate 0") == 1 << 8);
  CHECK(runVoca("synth --out " + (scratch / "d").string() + " --psf-sigma 9") == 1 << 8);
  CHECK(runVoca("synth --out " + (scratch / "f").string() + " --exposure -1") == 1 << 8);
  CHECK(runVoca("synth --out " + (scratch / "g").string() + " --exposure 60") == 1 << 8);  // > one 50 ms period
  CHECK(runVoca("synth --out " + (scratch / "h").string() + " --gain 0") == 1 << 8);
  CHECK(runVoca("synth --out " + (scratch / "i").string() + " --start 2") == 1 << 8);  // needs --trajectory
  // Too long to render: refused before any per-frame memory (1e8 s once grew without bound).
  for (const char* seconds : {"1e8", "1e9"}) {
    const voca::test::CommandOutput result =
        voca::test::runVocaOutput("synth --out " + (scratch / "j").string() + " --seconds " + seconds);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find("at most 1000000 frames") != std::string::npos);
    CHECK(!fs::exists(scratch / "j"));
  }
  // Cameras of two sizes: refused before rendering, as `voca run` would refuse the result.
  voca::StereoRig uneven = voca::synth::eurocRig();
  uneven.cameras[1].width = 640;
  const fs::path uneven_calib = scratch / "uneven.json";
  voca::saveBasaltCalibration(uneven, uneven_calib);
  const voca::test::CommandOutput sizes =
      voca::test::runVocaOutput("synth --out " + (scratch / "l").string() + " --camera " + uneven_calib.string());
  INFO(sizes.text);
  CHECK(sizes.exit_code == 1);
  CHECK(sizes.text.find("cam0 is 752x480 but cam1 640x480") != std::string::npos);
  CHECK(!fs::exists(scratch / "l"));
  // Two sources of motion at once is a usage error (exit code 2), not a silent choice.
  CHECK(runVoca("synth --out " + (scratch / "e").string() + " --motion gentle --trajectory gt.txt") == 2 << 8);
  CHECK(runVoca("synth --out " + (scratch / "k").string() + " --no-such-option") == 2 << 8);
  CHECK(runVoca("synth --help") == 0);
}

TEST_CASE("voca synth --camera: a path that does not exist is named as not found; other names get the choices") {
  voca::test::ScratchDir scratch("synth-e2e-camera");
  for (const std::string camera : {"calib/nonexistent.json", "nonexistent.yaml", "/no/such/mav0"}) {
    const voca::test::CommandOutput result =
        voca::test::runVocaOutput("synth --out " + (scratch / "out").string() + " --camera " + camera);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find("--camera " + camera + ": calibration file or folder not found") != std::string::npos);
    CHECK(result.text.find("expected 'euroc'") == std::string::npos);
  }
  const voca::test::CommandOutput preset =
      voca::test::runVocaOutput("synth --out " + (scratch / "out").string() + " --camera eurocc");
  INFO(preset.text);
  CHECK(preset.exit_code == 1);
  CHECK(preset.text.find("--camera 'eurocc': expected 'euroc', 'tumvi' or a calibration file/folder") !=
        std::string::npos);
  CHECK(!fs::exists(scratch / "out"));
}

TEST_CASE("a stopped synth run keeps the frames it rendered as a complete, shorter sequence") {
  voca::test::ScratchDir scratch("synth-stopped");
  voca::pipeline::SynthOptions options;
  options.out = scratch / "seq";
  options.seconds = 2.0;  // 40 frames planned
  options.supersample = 1;
  options.progress = false;
  int asked = 0;
  options.stop_requested = [&] { return ++asked > 6; };
  const voca::pipeline::SynthResult result = voca::pipeline::synthesizeSequence(options);
  CHECK(result.stopped);
  CHECK(result.frames == 6);
  CHECK(result.planned_frames == 40);
  // The readers accept it as a six-frame sequence with its ground truth and calibration.
  const voca::Dataset dataset = voca::openDataset(options.out);
  CHECK(dataset.frames.size() == 6);
  REQUIRE(dataset.ground_truth);
  const voca::Trajectory truth = voca::loadTrajectory(*dataset.ground_truth);
  REQUIRE(truth.poses.size() == 6);
  CHECK(truth.poses.back().t_ns == dataset.frames.back().t_ns);
  REQUIRE(dataset.calibration);
  CHECK(voca::loadCalibration(*dataset.calibration).cameras.size() == 2);
}

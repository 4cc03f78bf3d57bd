// The `voca` commands a user runs, through the binary, with their output checked: odd frame sizes
// (KITTI 00-02 are 1241x376) through synth, encode, decode, track, run, eval, bench and demo, on
// one small sequence so the whole chain costs seconds.

#include <array>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>

#include <nlohmann/json.hpp>

#include "drivers/decode/video_reader.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "tests/test_support.h"
#include "voca/camera/generic_camera.h"
#include "voca/trajectory/trajectory.h"

namespace fs = std::filesystem;
using voca::test::runVocaOutput;

namespace {

// Shows the command's output when it failed, so a failure explains itself.
void requireSuccess(const voca::test::CommandOutput& result, const std::string& what) {
  INFO(what << " printed:\n" << result.text);
  REQUIRE(result.exit_code == 0);
}

// Whether text has this whole line.
bool hasLine(const std::string& text, const std::string& line) {
  return text.starts_with(line + "\n") || text.find("\n" + line + "\n") != std::string::npos;
}

std::size_t countLines(const fs::path& path) {
  std::ifstream in(path);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty() && line[0] != '#') ++lines;
  }
  return lines;
}

// A small odd-sized pinhole stereo rig with an 11 cm baseline; cam0 is the body frame.
voca::StereoRig oddRig(int width, int height) {
  const double f = 0.6 * width;
  const std::vector<double> params{f, f, 0.5 * (width - 1), 0.5 * (height - 1)};
  voca::StereoRig rig;
  rig.body_frame = "cam0";
  voca::SE3d cam0_from_cam1;
  cam0_from_cam1.translation() = Eigen::Vector3d(0.11, 0.0, 0.0);
  rig.cameras.push_back({voca::GenericCamera<double>::fromParams("pinhole", params), width, height, voca::SE3d()});
  rig.cameras.push_back({voca::GenericCamera<double>::fromParams("pinhole", params), width, height, cam0_from_cam1});
  return rig;
}

}  // namespace

TEST_CASE("odd frame sizes work end to end: synth, encode, decode, track, run --encode, eval, bench, demo") {
  constexpr int kWidth = 321, kHeight = 161;
  voca::test::ScratchDir scratch("cli-odd");
  voca::saveBasaltCalibration(oddRig(kWidth, kHeight), scratch / "odd_calib.json");
  // The layout `voca demo --out <folder>` uses, so the demo can reuse this sequence at the end.
  const fs::path demo = scratch / "demo", raw = demo / "synth", video = demo / "video";
  requireSuccess(runVocaOutput("synth --out " + raw.string() + " --camera " + (scratch / "odd_calib.json").string() +
                               " --motion gentle --seconds 1.5 --supersample 1"),
                 "voca synth");
  const voca::Dataset dataset = voca::openDataset(raw);
  REQUIRE(dataset.frames.size() == 30);
  const voca::GrayImage first = voca::readPngGray(dataset.frames.front().left);
  REQUIRE(first.width() == kWidth);
  REQUIRE(first.height() == kHeight);

  // voca encode: the videos and the calibration keep the odd size.
  const auto encoded =
      runVocaOutput("encode " + raw.string() + " --out " + video.string() + " --bitrate 500k --single-pass");
  requireSuccess(encoded, "voca encode");
  {
    // stderr is a file here, not a terminal: the progress is whole lines (each pass's first and last
    // state), not '\r' rewrites glued into one endless line.
    INFO("voca encode printed:\n" << encoded.text);
    CHECK(encoded.text.find('\r') == std::string::npos);
    for (const std::string camera : {"cam0", "cam1"}) {
      CHECK(hasLine(encoded.text, camera + " pass 1/1: frame 1/30 (3%)"));
      CHECK(hasLine(encoded.text, camera + " pass 1/1: frame 30/30 (100%)"));
    }
  }
  const voca::StereoRig encoded_rig = voca::loadCalibration(video / "calib.json");
  CHECK(encoded_rig.cameras[0].width == kWidth);
  CHECK(encoded_rig.cameras[0].height == kHeight);
  const voca::Dataset video_dataset = voca::openDataset(video);
  REQUIRE(video_dataset.layout == voca::DatasetLayout::kVocaVideo);
  voca::decode::StereoVideoReader reader(video_dataset);
  voca::decode::DecodedFrame left, right;
  std::size_t decoded = 0, with_vectors = 0;
  while (reader.next(left, right)) {
    ++decoded;
    CHECK(left.luma.width() == kWidth);
    CHECK(left.luma.height() == kHeight);
    CHECK(right.luma.width() == kWidth);
    CHECK(left.motion.width() == kWidth);
    if (left.motion.hasVectors()) ++with_vectors;
  }
  CHECK(decoded == 30);
  CHECK(with_vectors >= 25);  // every P-frame carries vectors; only the first frame is intra

  // voca track on the odd-sized video: statistics for every frame.
  const auto tracked = runVocaOutput("track " + video.string() + " --mode mv_parallel_of");
  requireSuccess(tracked, "voca track");
  INFO("voca track printed:\n" << tracked.text);
  CHECK(tracked.text.find("30 frames") != std::string::npos);

  // voca run with on-the-fly encoding (the KITTI 00-02 case of the issue), then voca eval.
  const fs::path trajectory = scratch / "traj.txt";
  const auto ran = runVocaOutput("run " + raw.string() + " --encode 500k --out " + trajectory.string());
  requireSuccess(ran, "voca run");
  {
    // Both progress lines of the run, the encoding's and the VO's, as whole lines in a log.
    INFO("voca run printed:\n" << ran.text);
    CHECK(ran.text.find('\r') == std::string::npos);
    CHECK(hasLine(ran.text, "cam0 pass 1/2: frame 1/30 (3%)"));
    CHECK(hasLine(ran.text, "cam1 pass 2/2: frame 30/30 (100%)"));
    CHECK(ran.text.find("\nframe 30/30: ") != std::string::npos);
  }
  CHECK(countLines(trajectory) == 30);
  REQUIRE(dataset.ground_truth);
  const auto evaluated = runVocaOutput("eval --gt " + dataset.ground_truth->string() + " --est " + trajectory.string() +
                                       " --json " + (scratch / "report.json").string());
  requireSuccess(evaluated, "voca eval");
  INFO("voca eval printed:\n" << evaluated.text);
  CHECK(evaluated.text.find("ATE") != std::string::npos);
  // The odd-sized chain estimates as well as an even one: the gentle 1.5 s motion is tracked to
  // about 3 mm ATE here; 3 cm still catches a pixel shift or a dropped column in the pipeline.
  std::ifstream report_file(scratch / "report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  CHECK(report.at("ate").at("count").get<int>() == 30);
  CHECK(report.at("ate").at("rmse").get<double>() < 0.03);

  // voca bench decode on the odd-sized video, one timed run per variant.
  const auto bench = runVocaOutput("bench decode " + (video / "mav0" / "cam0" / "data.mp4").string() + " --repeat 1");
  requireSuccess(bench, "voca bench decode");
  INFO("voca bench printed:\n" << bench.text);
  CHECK(bench.text.find("fps") != std::string::npos);
  CHECK(bench.text.find("MV-only parse and deblocking-skipped vectors identical to full decode: yes") !=
        std::string::npos);
  CHECK(bench.text.find("this is one camera's video") != std::string::npos);
  // ... and on the folder: both cameras per stereo frame, with the target's verdict.
  const auto stereo_bench = runVocaOutput("bench decode " + video.string() + " --repeat 1");
  requireSuccess(stereo_bench, "voca bench decode (folder)");
  INFO("voca bench decode printed:\n" << stereo_bench.text);
  CHECK(stereo_bench.text.find("2 cameras") != std::string::npos);
  CHECK(stereo_bench.text.find("per stereo frame (both cameras)") != std::string::npos);
  CHECK(stereo_bench.text.find("MV-only parse and deblocking-skipped vectors identical to full decode: yes") !=
        std::string::npos);
  const std::size_t target = stereo_bench.text.find("target per stereo frame on one core, full decode + MV");
  REQUIRE(target != std::string::npos);
  const std::string verdict = stereo_bench.text.substr(stereo_bench.text.find("median: ", target) + 8, 3);
  CHECK((verdict == "met" || verdict == "mis"));

  // voca bench frontend: a row per mode (comma-separated list) with the target verdict, and with two
  // runs each run's own median below its row.
  const auto frontend =
      runVocaOutput("bench frontend " + video.string() + " --calib " + (scratch / "odd_calib.json").string() +
                    " --repeat 2 --modes none,mv_parallel_of");
  requireSuccess(frontend, "voca bench frontend");
  INFO("voca bench frontend printed:\n" << frontend.text);
  CHECK(frontend.text.find("\nnone ") != std::string::npos);
  CHECK(frontend.text.find("\nmv_parallel_of ") != std::string::npos);
  CHECK(frontend.text.find("\nmv ") == std::string::npos);
  const std::size_t run_medians = frontend.text.find("\n  each run's own median: ");
  REQUIRE(run_medians != std::string::npos);
  CHECK(frontend.text.find(", ", run_medians) < frontend.text.find(" ms\n", run_medians));
  CHECK(frontend.text.find("target per stereo frame on one core, every mode: median <= 4 ms") != std::string::npos);
  const auto frontend_no_runs = runVocaOutput("bench frontend " + video.string() + " --calib " +
                                              (scratch / "odd_calib.json").string() + " --repeat 0");
  CHECK(frontend_no_runs.exit_code != 0);
  CHECK(frontend_no_runs.text.find("--repeat: Value 0 not in range 1 to 100") != std::string::npos);

  // voca bench backend: the estimator timed alone on the frontend's real tracks of this video.
  const auto backend = runVocaOutput("bench backend " + video.string() + " --calib " +
                                     (scratch / "odd_calib.json").string() + " --warmup 10");
  requireSuccess(backend, "voca bench backend");
  INFO("voca bench backend printed:\n" << backend.text);
  CHECK(backend.text.find("backend on the frontend's tracks (mv_parallel_of mode") != std::string::npos);
  CHECK(backend.text.find("measured frames 20 (after 10 warm-up)") != std::string::npos);
  // Three runs by default: each frame's median, and each run's own median beside it.
  CHECK(backend.text.find("CPU time per frame (each frame's median of 3 runs): median ") != std::string::npos);
  CHECK(backend.text.find("each run's own median: ") != std::string::npos);
  CHECK(backend.text.find("target per stereo frame on one core: median <= 4 ms") != std::string::npos);
  // Fewer frames than the warm-up: a clear error, not a table of NaNs.
  const auto too_short = runVocaOutput("bench backend " + video.string() + " --calib " +
                                       (scratch / "odd_calib.json").string() + " --warmup 30");
  CHECK(too_short.exit_code != 0);
  CHECK(too_short.text.find("30 frames: the estimator needs more than the 30 warm-up frames") != std::string::npos);
  const auto no_runs = runVocaOutput("bench backend " + video.string() + " --calib " +
                                     (scratch / "odd_calib.json").string() + " --repeat 0");
  CHECK(no_runs.exit_code != 0);
  CHECK(no_runs.text.find("--repeat") != std::string::npos);

  // voca demo --reuse on this sequence: both VO variants side by side, trajectories and overlay. The
  // settings recorded with the sequences differ from the demo's defaults: they are reused as they are,
  // with a warning, and the summary describes them, not the command line.
  std::ofstream(demo / "synth.settings") << "gentle\n1.5\n";
  std::ofstream(demo / "video.settings") << "800k\n";
  const auto demo_run = runVocaOutput("demo --out " + demo.string() + " --reuse");
  requireSuccess(demo_run, "voca demo");
  INFO("voca demo printed:\n" << demo_run.text);
  CHECK(demo_run.text.find("[1/4] reusing") != std::string::npos);
  CHECK(demo_run.text.find("[2/4] reusing") != std::string::npos);
  CHECK(demo_run.text.find("rendering") == std::string::npos);
  CHECK(demo_run.text.find("was made with --motion and --seconds gentle 1.5, not as asked") != std::string::npos);
  CHECK(demo_run.text.find("was made with --bitrate 800k, not as asked") != std::string::npos);
  CHECK(demo_run.text.find("VOCA-RT demo: 30 frames of `gentle` motion, stereo encoded at 800k per camera") !=
        std::string::npos);
  CHECK(demo_run.text.find("ATE [m]") != std::string::npos);
  CHECK(countLines(demo / "traj_none.txt") == 30);
  CHECK(countLines(demo / "traj_mv_parallel_of.txt") == 30);
  CHECK(fs::file_size(demo / "overlay_mv_parallel_of.mp4") > 0);
}

TEST_CASE("voca encode on a folder with a missing and a corrupt image: warning, error on its own line, no folder") {
  voca::test::ScratchDir dir("cli-encode-bad");
  const fs::path raw = dir / "raw";
  {
    voca::EurocWriter writer(raw);
    const voca::GrayImage image(64, 48, 90);
    const std::array<voca::GrayView, 2> views = {image.view(), image.view()};
    for (std::int64_t i = 1; i <= 8; ++i) writer.addFrame(i * 50'000'000, views);
    writer.finish();
  }
  const voca::Dataset dataset = voca::openDataset(raw);
  fs::remove(dataset.frames[1].right);
  // Late enough that the progress line is on screen when the encoding stops.
  const fs::path corrupt = dataset.frames[6].left;
  std::ofstream(corrupt, std::ios::binary | std::ios::trunc) << "not a png";

  const fs::path out = dir / "out";
  const voca::test::CommandOutput result =
      runVocaOutput("encode " + raw.string() + " --out " + out.string() + " --single-pass");
  INFO(result.text);
  CHECK(result.exit_code == 1);
  // The frame left out is said, as `voca run` says it.
  CHECK(result.text.find("warning: 1 cam0 images have no cam1 image with the same timestamp and were skipped") !=
        std::string::npos);
  // The error starts a line: the progress line before it was ended.
  const std::size_t error = result.text.find("voca encode: error: " + corrupt.string());
  REQUIRE(error != std::string::npos);
  REQUIRE(error > 0);
  CHECK(result.text[error - 1] == '\n');
  CHECK(result.text.find("cam0 pass 1/1: frame") < error);
  CHECK(!fs::exists(out));
}

TEST_CASE("voca encode --pix-fmt gray: a luma-only encoding that decodes with vectors; other codecs refuse it") {
  voca::test::ScratchDir dir("cli-encode-gray");
  const fs::path raw = dir / "raw";
  requireSuccess(runVocaOutput("synth --out " + raw.string() + " --motion gentle --seconds 1"), "voca synth");
  const fs::path video = dir / "video";
  const auto encoded =
      runVocaOutput("encode " + raw.string() + " --out " + video.string() + " --single-pass --pix-fmt gray");
  requireSuccess(encoded, "voca encode --pix-fmt gray");
  CHECK(encoded.text.find("gray 4:0:0") != std::string::npos);
  voca::decode::VideoReader reader(video / "mav0" / "cam0" / "data.mp4", {}, {});
  voca::decode::DecodedFrame frame;
  int frames = 0, with_vectors = 0;
  while (reader.next(frame)) {
    ++frames;
    with_vectors += frame.motion.hasVectors() ? 1 : 0;
  }
  CHECK(frames == 20);
  CHECK(with_vectors == frames - 1);  // every frame after the first I-frame

  const fs::path refused = dir / "refused";
  const auto mpeg4 = runVocaOutput("encode " + raw.string() + " --out " + refused.string() +
                                   " --single-pass --codec mpeg4 --pix-fmt gray");
  INFO(mpeg4.text);
  CHECK(mpeg4.exit_code == 1);
  CHECK(mpeg4.text.find("--pix-fmt gray: only libx264 codes frames without chroma; --codec mpeg4 takes yuv420p") !=
        std::string::npos);
  CHECK(!fs::exists(refused));
}

TEST_CASE("a path the system refuses is an error naming it, not an internal error") {
  voca::test::ScratchDir dir("cli-fs-error");
  const fs::path suite = dir / "suite.json";
  std::ofstream(suite) << R"({"name": "s", "sequences": [{"name": "b", "path": ")" << dir.path().string()
                       << R"("}], "bitrates": ["raw"], "modes": ["none"]})";
  const fs::path file = dir / "a-file";
  std::ofstream(file) << "x";
  // The output folder would have to be created where a file is.
  const voca::test::CommandOutput result = runVocaOutput("bench suite " + suite.string() + " -o " + file.string());
  INFO(result.text);
  CHECK(result.exit_code == 1);
  CHECK(result.text.find("voca bench: error: ") != std::string::npos);
  CHECK(result.text.find(file.string()) != std::string::npos);
  CHECK(result.text.find("internal error") == std::string::npos);
}

TEST_CASE("an output that is an input file, in the dataset's data folder, or another output's file is refused first") {
  voca::test::ScratchDir dir("cli-outputs-apart");
  const fs::path raw = dir / "raw";
  const fs::path video = dir / "video";
  REQUIRE(voca::test::runVoca("synth --out " + raw.string() + " --seconds 0.3 --motion gentle --supersample 1") == 0);
  REQUIRE(voca::test::runVoca("encode " + raw.string() + " --out " + video.string() +
                              " --bitrate 500k --single-pass") == 0);
  const fs::path left_video = video / "mav0" / "cam0" / "data.mp4";
  const fs::path ground_truth = video / "mav0" / "state_groundtruth_estimate0" / "data.csv";
  const auto video_size = fs::file_size(left_video);
  const auto gt_size = fs::file_size(ground_truth);
  const auto refused = [&](const std::string& args, const std::string& message) {
    const voca::test::CommandOutput result = runVocaOutput(args);
    INFO(args);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find(message) != std::string::npos);
  };
  // The run's outputs against what it reads: before, these truncated the video or replaced the ground truth.
  refused("run " + video.string() + " -o " + left_video.string(),
          "the trajectory file " + left_video.string() + " lies in the dataset's mav0 folder");
  refused("run " + video.string() + " -o " + ground_truth.string(), "lies in the dataset's mav0 folder");
  refused("track " + video.string() + " --overlay " + left_video.string(), "the overlay video");
  refused("run " + video.string() + " -o " + (dir / "t.txt").string() + " --gt " + (dir / "gt.csv").string() +
              " --stats " + (dir / "gt.csv").string(),
          "the statistics file " + (dir / "gt.csv").string() + " is the ground truth");
  // Two outputs, one file (also spelt differently).
  refused("run " + video.string() + " -o " + (dir / "same.txt").string() + " --stats " +
              (dir / "x" / ".." / "same.txt").string(),
          "the trajectory file and the statistics file name the same file");
  refused("run " + video.string() + " -o \"\"", "--out: an empty path");
  CHECK(fs::file_size(left_video) == video_size);
  CHECK(fs::file_size(ground_truth) == gt_size);
  CHECK_FALSE(fs::exists(dir / "same.txt"));
  // An output that cannot be written is refused before the run, with the reason (the statistics were
  // written only after the whole run).
  refused("run " + video.string() + " -o " + (dir / "t.txt").string() + " --stats " +
              (dir / "no-such-folder" / "s.json").string(),
          "cannot write the statistics file " + (dir / "no-such-folder" / "s.json").string() + ": the folder " +
              (dir / "no-such-folder").string() + " does not exist");
  refused("run " + video.string() + " -o " + dir.path().string(),
          "cannot write the trajectory file " + dir.path().string() + ": it is a folder");
  // A trajectory beside the data is fine.
  CHECK(voca::test::runVoca("run " + video.string() + " -o " + (video / "trajectory.txt").string()) == 0);

  // voca encode: an output folder holding the input (given as its mav0 folder), --decoded-png onto the input.
  refused("encode " + (raw / "mav0").string() + " --out " + raw.string() + " --single-pass",
          "the output folder " + raw.string() + " holds the input dataset");
  refused("encode " + raw.string() + " --out " + (dir / "enc").string() + " --decoded-png " + raw.string(),
          "--decoded-png " + raw.string() + " is the input dataset");
  refused("encode " + raw.string() + " --out " + (dir / "enc").string() + " --decoded-png " + (dir / "enc").string(),
          "is the output folder");
  CHECK(fs::exists(raw / "mav0" / "cam0" / "data.csv"));
  CHECK_FALSE(fs::exists(dir / "enc"));
  // voca synth over a video dataset, voca eval's report over its estimate.
  refused("synth --out " + video.string() + " --seconds 0.2", "holds a video dataset");
  CHECK(fs::file_size(ground_truth) == gt_size);
  refused("eval --gt " + ground_truth.string() + " --est " + (video / "trajectory.txt").string() + " --json " +
              (video / "trajectory.txt").string(),
          "--json " + (video / "trajectory.txt").string() + " is --est");
  refused("eval --gt " + ground_truth.string() + " --est " + (video / "trajectory.txt").string() + " --json " +
              (dir / "no-such-folder" / "r.json").string(),
          "cannot write --json " + (dir / "no-such-folder" / "r.json").string() + ": the folder");

  // voca stream to a file: before, `stream raw raw/mav0/cam0/data.csv` replaced the frame list with the stream.
  const fs::path frame_list = raw / "mav0" / "cam0" / "data.csv";
  const auto frame_list_size = fs::file_size(frame_list);
  refused("stream " + raw.string() + " " + frame_list.string() + " --frames 2",
          "the output file " + frame_list.string() + " lies in the dataset's mav0 folder");
  refused("stream " + raw.string() + " file://" + fs::absolute(raw / "calib.json").string() + " --frames 2",
          "is the dataset's calibration");
  refused("stream " + raw.string() + " " + (dir / "no-such-folder" / "s.ts").string() + " --frames 2",
          "cannot write the output file " + (dir / "no-such-folder" / "s.ts").string() + ": the folder");
  CHECK(fs::file_size(frame_list) == frame_list_size);
  // voca mv: its pictures among the dataset's files, or its folder on the video it draws.
  refused("mv " + video.string() + " --out " + (video / "mav0" / "cam0").string() + " --frames 0:1",
          "the output folder " + (video / "mav0" / "cam0").string() + " lies in the dataset's mav0 folder");
  refused("mv " + left_video.string() + " --out " + left_video.string() + " --frames 0:1", "is the video");
  CHECK_FALSE(fs::exists(video / "mav0" / "cam0" / "mv_000000.png"));
  CHECK(fs::file_size(left_video) == video_size);
}

TEST_CASE("pacing and waiting bounds: NaN, infinite and negative values are refused by name") {
  voca::test::ScratchDir dir("cli-bounds");
  const std::string run = "run " + dir.path().string() + " -o " + (dir / "t.txt").string();
  for (const char* speed : {"nan", "-1", "0", "inf"}) {
    const voca::test::CommandOutput result = runVocaOutput(run + " --realtime --speed " + speed);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find("--speed: expected a factor above 0 and at most 1e6") != std::string::npos);
  }
  for (const char* wait : {"--stream-wait inf", "--stream-wait nan", "--stream-timeout 1e300"}) {
    const voca::test::CommandOutput result = runVocaOutput(run + " " + wait);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find("expected seconds above 0 and at most 86400") != std::string::npos);
  }
  // The tracker's capacity, named by its option before the input is opened.
  for (const char* points : {"0", "70000"}) {
    const voca::test::CommandOutput result = runVocaOutput(run + " --max-points " + points);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find("--max-points " + std::string(points) + ": expected 1 to 65536 points per camera") !=
          std::string::npos);
  }
}

TEST_CASE("number options say what they expect: no 309-digit bound, text that is no number named as such") {
  voca::test::ScratchDir dir("cli-numbers");
  const fs::path trajectory = dir / "t.txt";
  {
    std::ofstream file(trajectory);
    for (int i = 0; i < 20; ++i) file << 0.05 * i << ' ' << 0.1 * i << " 0 0 0 0 0 1\n";
  }
  const std::string eval = "eval --gt " + trajectory.string() + " --est " + trajectory.string();
  const std::pair<std::string, std::string> cases[] = {
      {eval + " --ate-divergence 0", "--ate-divergence: expected a number above 0, got 0"},
      {eval + " --rte-divergence -1", "--rte-divergence: expected a number above 0, got -1"},
      {eval + " --expected-frames 0", "--expected-frames: expected a number above 0, got 0"},
      {eval + " --max-diff -1", "--max-diff: expected a number of 0 or more, got -1"},
      {eval + " --max-diff abc", "--max-diff: expected a number, got 'abc'"},
      {eval + " --max-diff nan", "--max-diff: expected a number, got 'nan'"},
      {"bench backend --warmup -1", "--warmup: expected a number of 0 or more, got -1"},
      {"bench backend --synthetic --motion 0", "--motion: expected a number above 0, got 0"},
      {"bench backend --synthetic --noise -1", "--noise: expected a number of 0 or more, got -1"},
      {"bench frontend --frames -1", "--frames: expected a number of 0 or more, got -1"},
      {"bench pipeline --frames -1", "--frames: expected a number of 0 or more, got -1"},
  };
  for (const auto& [command_line, message] : cases) {
    const std::string& args = command_line;  // INFO captures it, which clang 14 allows only for a variable
    const voca::test::CommandOutput result = runVocaOutput(args);
    INFO(args);
    INFO(result.text);
    CHECK(result.exit_code == 2);  // the command line does not parse: nothing ran
    CHECK(result.text.find(message) != std::string::npos);
    CHECK(result.text.find("17976931348623157") == std::string::npos);
  }
  // The bounds themselves pass.
  CHECK(runVocaOutput(eval + " --max-diff 0 --expected-frames 2").exit_code == 0);
  // A missing input is bad input like in the other commands: exit code 1, named.
  const std::pair<std::string, std::string> missing[] = {
      {"eval --gt " + (dir / "nope.txt").string() + " --est " + trajectory.string(),
       "--gt " + (dir / "nope.txt").string() + ": no such file"},
      {"eval --gt " + trajectory.string() + " --est " + dir.path().string(),
       "--est " + dir.path().string() + ": a folder, not a file"},
      {eval + " --est-times " + (dir / "times.txt").string(), "--est-times " + (dir / "times.txt").string()},
  };
  for (const auto& [command_line, message] : missing) {
    const std::string& args = command_line;  // INFO captures it, which clang 14 allows only for a variable
    const voca::test::CommandOutput result = runVocaOutput(args);
    INFO(args);
    INFO(result.text);
    CHECK(result.exit_code == 1);
    CHECK(result.text.find("voca eval: error: " + message) != std::string::npos);
  }
}

TEST_CASE("a file that is no recording is named as such, not as 'not a folder'") {
  voca::test::ScratchDir dir("cli-not-recording");
  std::ofstream(dir / "empty.ts").close();
  std::ofstream(dir / "text.ts") << "not a transport stream\n";
  for (const char* name : {"empty.ts", "text.ts"}) {
    for (const std::string& command : {"run -o " + (dir / "t.txt").string(), std::string("track")}) {
      const voca::test::CommandOutput result = runVocaOutput(command + " " + (dir / name).string());
      INFO(result.text);
      CHECK(result.exit_code == 1);
      CHECK(result.text.find((dir / name).string() +
                             (std::string(name) == "empty.ts" ? ": an empty file" : ": a file") +
                             ", not an MPEG-TS recording of `voca stream`") != std::string::npos);
    }
  }
  CHECK_FALSE(fs::exists(dir / "t.txt"));
}

TEST_CASE("a misspelt command is named with the commands there are; -o is --out everywhere") {
  const voca::test::CommandOutput result = runVocaOutput("rnu --help");
  INFO(result.text);
  CHECK(result.exit_code == 2);
  CHECK(result.text.find("voca: unknown command 'rnu' (the commands: demo, ") != std::string::npos);
  CHECK(result.text.find(", run, ") != std::string::npos);
  CHECK(runVocaOutput("run --help").exit_code == 0);
  // -o is --out in every command that writes.
  for (const char* command : {"synth", "mv", "encode", "run", "demo", "record", "live", "bench suite"}) {
    INFO(command);
    CHECK(runVocaOutput(std::string(command) + " --help").text.find("-o,--out") != std::string::npos);
  }
}

TEST_CASE("voca demo checks its options before making its folder, and a stop removes a shortened rendering") {
  voca::test::ScratchDir scratch("cli-demo-checks");
  const fs::path out = scratch / "demo";
  const auto bad_motion = runVocaOutput("demo --out " + out.string() + " --motion wobbly");
  CHECK(bad_motion.exit_code == 2);
  CHECK(bad_motion.text.find("--motion: wobbly not in {gentle,fast-rotation,aggressive}") != std::string::npos);
  const auto bad_rate = runVocaOutput("demo --out " + out.string() + " --bitrate 5x");
  CHECK(bad_rate.exit_code == 1);
  CHECK(bad_rate.text.find("bitrate '5x'") != std::string::npos);
  CHECK_FALSE(fs::exists(out));

  // Ctrl-C as the rendering starts: the rendering stops, and its shorter sequence is removed so that
  // --reuse cannot take it for the demo's.
  const fs::path log = scratch / "log.txt";
  const pid_t pid = voca::test::spawnVoca("demo --out " + out.string(), scratch.path(), log);
  REQUIRE(voca::test::signalWhenWritten(pid, log, SIGINT));
  CHECK(voca::test::waitExitCode(pid) == 130);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CAPTURE(text);
  CHECK(text.find("voca demo: stopped; the shortened rendering") != std::string::npos);
  CHECK_FALSE(fs::exists(out / "synth"));
}

// The VO through the staged pipeline on real and rendered sequences: pipelined runs write the same
// trajectory as single-threaded ones byte for byte; damaged packets are skipped and listed (or stop
// the run with --strict); a failing or early-ending source leaves a clean, parseable result; SIGINT
// and SIGTERM sent to `voca run` write everything estimated so far and remove temporary folders.

#include <doctest/doctest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "drivers/decode/demuxer.h"
#include "drivers/encode/dataset_encoder.h"
#include "drivers/source/dataset_source.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "formats/trajectory/trajectory_io.h"
#include "pipeline/stages/source_stage.h"
#include "pipeline/vo/vo_runner.h"
#include "tests/test_support.h"
#include "tests/test_video_damage.h"

using namespace voca;
namespace fs = std::filesystem;

namespace {

std::string fileText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A rendered 2 s sequence with fast motion and its 500 kbit/s encoding, made once per test run.
struct Rendered {
  test::ScratchDir dir{"pipeline-e2e"};
  fs::path raw = dir / "synth";
  fs::path video = dir / "video";
  Rendered() {
    REQUIRE(test::renderSynth(raw, "--motion aggressive --seconds 2 --supersample 1") == 0);
    REQUIRE(test::runVoca("encode " + raw.string() + " --out " + video.string() + " --bitrate 500k") == 0);
  }
};

const Rendered& rendered() {
  static const Rendered sequence;
  return sequence;
}

pipeline::VoRunOptions quietRun(const fs::path& input, const fs::path& trajectory, int threads) {
  pipeline::VoRunOptions options;
  options.input = input;
  options.trajectory_file = trajectory;
  options.progress = false;
  options.pipeline_options.threads = threads;
  return options;
}

// Runs with one thread, two threads (the frontend's right camera on a helper), and one thread per
// stage without and with the helper; the four files must be identical.
// Under a sanitizer the layouts run the first 8 frames: enough for every thread to hand frames on
// and for the backend's depth to reach the frontend (two frames after each frame's estimate), at a
// fraction of a whole sequence's time (under TSan a run's setup takes 1.3 s, each frame 0.28 s).
void expectSameTrajectory(const std::string& name, pipeline::VoRunOptions options) {
  if (!test::kSanitizer.empty()) options.max_frames = 8;
  test::ScratchDir dir("pipeline-determinism");
  std::string reference;
  const std::pair<int, int> layouts[] = {{1, 1}, {2, 2}, {0, 1}, {0, 2}};  // threads, frontend camera threads
  for (const auto& layout : layouts) {
    const int threads = layout.first;  // variables, not bindings: INFO captures them (clang 14)
    const int camera_threads = layout.second;
    options.trajectory_file = dir / ("traj_" + std::to_string(threads) + "_" + std::to_string(camera_threads) + ".txt");
    options.pipeline_options.threads = threads;
    options.frontend_camera_threads = camera_threads;
    const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
    INFO(name << ", threads option " << threads << " (" << result.pipeline_report.threads << " threads), frontend on "
              << camera_threads);
    REQUIRE_FALSE(result.pipeline_report.error);
    CHECK(result.frontend_camera_threads == camera_threads);
    CHECK(result.pipeline_report.dropped == 0);
    CHECK(result.frames == result.pipeline_report.produced);
    const std::string text = fileText(options.trajectory_file);
    CHECK(std::count(text.begin(), text.end(), '\n') == result.frames + 1);  // header + a row per frame
    if (threads == 1) {
      reference = text;
    } else {
      CHECK(text == reference);
    }
  }
}

// Copies a video folder (small: two short videos and text files).
void copyFolder(const fs::path& from, const fs::path& to) { fs::copy(from, to, fs::copy_options::recursive); }

// Wraps a dataset source: fails with "device disappeared" at frame fail_at, or ends at end_at.
class FaultySource final : public StereoSource {
 public:
  FaultySource(std::unique_ptr<StereoSource> inner, std::int64_t fail_at, std::int64_t end_at)
      : inner_(std::move(inner)), fail_at_(fail_at), end_at_(end_at) {}
  const SourceInfo& info() const override { return inner_->info(); }
  bool next(EncodedStereoPacket& packet) override {
    if (count_ == fail_at_) throw RuntimeFailure("camera: device disappeared");
    if (count_ == end_at_) return false;
    ++count_;
    return inner_->next(packet);
  }

 private:
  std::unique_ptr<StereoSource> inner_;
  std::int64_t fail_at_, end_at_;
  std::int64_t count_ = 0;
};

// Starts `voca <args>` with TMPDIR set, output to a log; returns the pid.
std::size_t countRows(const fs::path& trajectory) {
  const std::string text = fileText(trajectory);
  const std::size_t lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
  return lines > 0 ? lines - 1 : 0;  // the header line
}

}  // namespace

TEST_CASE("pipeline e2e: pipelined runs write the single-threaded trajectory byte for byte") {
  SUBCASE("rendered sequence at 500 kbit/s, VOCA and baseline modes") {
    pipeline::VoRunOptions options = quietRun(rendered().video, {}, 1);
    expectSameTrajectory("synthetic mv_parallel_of", options);
    options.mode = PriorMode::kNone;
    expectSameTrajectory("synthetic none", options);
  }
  SUBCASE("micro EuRoC encoded at 500 kbit/s") {
    const auto data = test::sharedData("euroc_v101_micro");
    if (!data) return;
    // Encoded once, so the three runs decode the same video.
    test::ScratchDir dir("pipeline-euroc");
    REQUIRE(encode::encodeForReplay(*data, dir / "video", 500000, std::nullopt, false, {}));
    expectSameTrajectory("micro EuRoC 500k", quietRun(dir / "video", {}, 1));
  }
  SUBCASE("KITTI 06 raw: the stereo guess uses the backend's depth through the fixed-lag channel") {
    const auto data = test::sharedData("kitti06_first51/sequences/06");
    if (!data) return;
    expectSameTrajectory("KITTI 06", quietRun(*data, {}, 1));
  }
}

TEST_CASE("pipeline e2e: --frontend-threads takes auto, 1 or 2, names anything else; the helper pins and traces") {
  test::ScratchDir dir("pipeline-frontend-threads");
  const std::string run = "run " + rendered().video.string() + " --frames 12 -o " + (dir / "traj.txt").string();
  const test::CommandOutput bad = test::runVocaOutput(run + " --frontend-threads 3");
  INFO(bad.text);
  CHECK(bad.exit_code == 1);
  CHECK(bad.text.find("--frontend-threads: expected auto, 1 or 2, got \"3\"") != std::string::npos);
  const test::CommandOutput helped = test::runVocaOutput(run + " --frontend-threads 2");
  INFO(helped.text);
  CHECK(helped.exit_code == 0);
  CHECK(helped.text.find("(and a frontend helper sharing the tracking)") != std::string::npos);
  const test::CommandOutput single = test::runVocaOutput(run + " --threads 1");
  CHECK(single.exit_code == 0);
  CHECK(single.text.find("frontend helper") == std::string::npos);  // auto: one thread runs everything

  // The helper's own pin asks for it (auto) and is kept when refused; its slices are in the trace.
  const test::CommandOutput pinned =
      test::runVocaOutput(run + " --pin frontend.helper:4095 --trace " + (dir / "trace.json").string() + " --stats " +
                          (dir / "stats.json").string());
  INFO(pinned.text);
  CHECK(pinned.exit_code == 0);
  CHECK(pinned.text.find("(and a frontend helper sharing the tracking)") != std::string::npos);
  CHECK(pinned.text.find("warning: thread 2 (frontend helper): core 4095") != std::string::npos);
  const std::string trace = fileText(dir / "trace.json");
  std::size_t helper_slices = 0;
  for (std::size_t at = trace.find("\"cat\":\"helper\""); at != std::string::npos;
       at = trace.find("\"cat\":\"helper\"", at + 1)) {
    ++helper_slices;
  }
  CHECK(helper_slices == 12);
  const nlohmann::json stats = nlohmann::json::parse(fileText(dir / "stats.json"));
  bool helper_row = false;
  for (const nlohmann::json& stage : stats.at("pipeline").at("stages")) {
    if (!stage.contains("helper")) continue;
    helper_row = true;
    CHECK(stage.at("name") == "frontend");
    CHECK(stage.at("helper").at("core") == 4095);
    CHECK(stage.at("helper").at("cpu").at("count") == 12);
  }
  CHECK(helper_row);
  const test::CommandOutput no_helper = test::runVocaOutput(run + " --frontend-threads 1 --pin frontend.helper:0");
  CHECK(no_helper.exit_code == 1);
  CHECK(no_helper.text.find("pin: frontend.helper: the frontend stage runs no helper thread") != std::string::npos);
}

TEST_CASE("pipeline e2e: a run without --config runs the shipped config of its input") {
  // The struct defaults are the paper's values; the shipped files differ where a measurement chose
  // otherwise (configs/README.md), and `voca run` promises the shipped euroc file by default.
  const pipeline::RunConfig euroc = pipeline::resolveRunConfig(std::nullopt);
  CHECK(euroc.name == "euroc (built in)");
  CHECK(euroc.config.frontend.prior_pyramid_levels == builtinConfig("euroc").frontend.prior_pyramid_levels);
  CHECK(euroc.config.frontend.prior_agree_radius_px == builtinConfig("euroc").frontend.prior_agree_radius_px);
  CHECK(euroc.config.frontend.prior_pyramid_levels != FrontendConfig{}.prior_pyramid_levels);
  const pipeline::RunConfig kitti = pipeline::resolveRunConfig(std::nullopt, true);
  CHECK(kitti.name == "kitti (built in)");
  CHECK(kitti.config.frontend.matching_default_depth_m == builtinConfig("kitti").frontend.matching_default_depth_m);
  CHECK(pipeline::resolveRunConfig(fs::path("tumvi")).config.backend.use_lm == builtinConfig("tumvi").backend.use_lm);
  CHECK_THROWS_AS(pipeline::resolveRunConfig(fs::path("no-such-config.json")), InputError);

  // And the run itself: no --config writes what --config euroc writes, byte for byte.
  test::ScratchDir dir("pipeline-default-config");
  pipeline::VoRunOptions options = quietRun(rendered().video, dir / "default.txt", 1);
  const pipeline::VoRunResult by_default = pipeline::runVisualOdometry(options);
  REQUIRE_FALSE(by_default.pipeline_report.error);
  // The shipped mode is in force: where a point has a vector only the vector's track runs (`mv`), so
  // no prior track was skipped for a plain one or rescued a plain one.
  CHECK(by_default.config.frontend.prior_mode == PriorMode::kMv);
  CHECK(by_default.frontend.tracked_prior > by_default.frontend.tracked_plain);
  CHECK(by_default.frontend.prior_confirmed == 0);
  CHECK(by_default.frontend.rescued == 0);
  options.trajectory_file = dir / "euroc.txt";
  options.config = fs::path("euroc");
  REQUIRE_FALSE(pipeline::runVisualOdometry(options).pipeline_report.error);
  CHECK(fileText(dir / "default.txt") == fileText(dir / "euroc.txt"));
  // In the paper's mode the same file's prior_agree_radius_px is in force, and the prior tracks it
  // skips reach the run's totals (the only positive check of that sum through the pipeline).
  options.trajectory_file = dir / "parallel.txt";
  options.mode = PriorMode::kMvParallelOf;
  const pipeline::VoRunResult parallel = pipeline::runVisualOdometry(options);
  REQUIRE_FALSE(parallel.pipeline_report.error);
  CHECK(parallel.frontend.prior_confirmed > 0);
}

TEST_CASE("pipeline e2e: a later start frame tracks from that frame; a video is still decoded from its start") {
  // The harness repeats a run from a few frames later to see past one run's luck; the repeat must
  // track exactly frames [start, end), and a video's earlier frames must still reach the decoder
  // (its P-frames reference them) without being tracked, counted as damaged or dropped.
  test::ScratchDir dir("pipeline-start-frame");
  const Dataset raw = openDataset(rendered().raw);
  REQUIRE(raw.frames.size() == 40);
  for (const fs::path& input : {rendered().video, rendered().raw}) {
    INFO(input.string());
    pipeline::VoRunOptions options = quietRun(input, dir / "from10.txt", 1);
    options.first_frame = 10;
    const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
    REQUIRE_FALSE(result.pipeline_report.error);
    CHECK(result.frames == 30);
    CHECK(result.pipeline_report.damaged == 0);
    CHECK(result.pipeline_report.dropped == 0);
    REQUIRE(result.rows.size() == 30);
    CHECK(result.rows.front().frame_index == 10);
    CHECK(result.rows.front().missing_before == 0);  // a start, not a gap
    REQUIRE(result.trajectory.poses.size() == 30);
    CHECK(result.trajectory.poses.front().t_ns == raw.frames[10].t_ns);
    CHECK(result.backend.resets == 0);
    if (input == rendered().video) CHECK(result.frontend.with_vector > 0);  // its vectors came through

    // --frames counts from the start; the pipelined run writes the same trajectory.
    options.max_frames = 12;
    options.pipeline_options.threads = 0;
    options.trajectory_file = dir / "from10_12.txt";
    const pipeline::VoRunResult limited = pipeline::runVisualOdometry(options);
    REQUIRE_FALSE(limited.pipeline_report.error);
    CHECK(limited.frames == 12);
    const std::string all = fileText(dir / "from10.txt");
    const std::string first12 = fileText(dir / "from10_12.txt");
    CHECK(all.compare(0, first12.size(), first12) == 0);

    options.first_frame = 40;
    options.max_frames = 0;
    CHECK_THROWS_WITH_AS(pipeline::runVisualOdometry(options), doctest::Contains("starting at frame 40"), InputError);
  }
}

TEST_CASE("pipeline e2e: prior_max_qp reaches the decoder: the quantisers are exported and the check distrusts") {
  // The decoder exports quantisers only when the config's check reads them; a run with the check on
  // must see them (no QP would silently trust every vector), a run with it off must not pay for them.
  test::ScratchDir dir("pipeline-qp");
  std::ofstream(dir / "qp.json") << R"({"frontend": {"prior_max_qp": 1}})";
  pipeline::VoRunOptions options = quietRun(rendered().video, dir / "qp.txt", 1);
  options.config = dir / "qp.json";
  const pipeline::VoRunResult strict = pipeline::runVisualOdometry(options);
  REQUIRE_FALSE(strict.pipeline_report.error);
  REQUIRE(strict.frontend.with_vector > 0);
  // QP 1 is below anything x264 chooses at 500 kbit/s: every vector with a quantiser is distrusted.
  CHECK(strict.frontend.distrusted == strict.frontend.with_vector);
  options.config = std::nullopt;
  options.trajectory_file = dir / "off.txt";
  const pipeline::VoRunResult off = pipeline::runVisualOdometry(options);
  CHECK(off.frontend.with_vector > 0);
  CHECK(off.frontend.distrusted == 0);
}

TEST_CASE("pipeline e2e: presmooth \"raw\" smooths the raw dataset's frames and leaves decoded ones alone") {
  // The source stage hands raw images on, the decode stage decoded ones; the frontend smooths by
  // what each frame is, so "raw" must write "always"'s trajectory on the raw dataset and "off"'s on
  // its video, byte for byte, while "always" and "off" differ on both.
  test::ScratchDir dir("pipeline-presmooth");
  for (const char* value : {"off", "raw", "always"}) {
    std::ofstream(dir / (std::string(value) + ".json")) << R"({"frontend": {"presmooth": ")" << value << R"("}})";
  }
  const auto trajectoryOf = [&](const fs::path& input, const std::string& value) {
    const fs::path out = dir / (input.filename().string() + "-" + value + ".txt");
    pipeline::VoRunOptions options = quietRun(input, out, 1);
    options.config = dir / (value + ".json");
    const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
    REQUIRE_FALSE(result.pipeline_report.error);
    return fileText(out);
  };
  for (const fs::path& input : {rendered().raw, rendered().video}) {
    CAPTURE(input);
    const std::string off = trajectoryOf(input, "off"), always = trajectoryOf(input, "always");
    REQUIRE_FALSE(off.empty());
    CHECK(off != always);
    CHECK(trajectoryOf(input, "raw") == (input == rendered().raw ? always : off));
  }
}

TEST_CASE("pipeline e2e: a damaged packet mid-stream is skipped and listed; --strict stops naming the frame") {
  test::ScratchDir dir("pipeline-damaged");
  const fs::path video = dir / "video";
  copyFolder(rendered().video, video);
  test::damagePacket(video / "mav0" / "cam0" / "data.mp4", 24);

  pipeline::VoRunOptions options = quietRun(video, dir / "traj.txt", 0);
  const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
  REQUIRE_FALSE(result.pipeline_report.error);
  REQUIRE_FALSE(result.pipeline_report.released.empty());
  CHECK(result.pipeline_report.released.front().frame_index == 24);
  CHECK(result.pipeline_report.released.front().reason == pipeline::ReleaseReason::kDamaged);
  // The paper's encoding has no I-picture after the first: every later picture is predicted from the
  // damaged one, shows its concealment moved along, and is skipped too.
  CHECK(result.frames == 24);
  CHECK(result.pipeline_report.damaged == 16);
  CHECK(countRows(dir / "traj.txt") == static_cast<std::size_t>(result.frames));
  CHECK(result.backend.resets == 0);

  options.strict = true;
  options.trajectory_file = dir / "strict.txt";
  const pipeline::VoRunResult strict = pipeline::runVisualOdometry(options);
  REQUIRE(strict.pipeline_report.error);
  CHECK(strict.pipeline_report.error->stage == "decode");
  CHECK(strict.pipeline_report.error->frame_index == 24);
  CHECK(strict.pipeline_report.error->message.find("cam0") != std::string::npos);
  // Everything before the damage was estimated and written.
  CHECK(countRows(dir / "strict.txt") == 24);
}

TEST_CASE("pipeline e2e: after a damaged picture the stream heals at the next I-picture and the run goes on") {
  // The rendered sequence encoded with an I-picture every 10 frames; the packet of frame 18 damaged.
  encode::silenceCodecLogs();
  test::ScratchDir dir("pipeline-damaged-gop");
  const fs::path video = dir / "video";
  encode::DatasetEncodeOptions encoding;
  encoding.settings.threads = 1;
  encoding.settings.two_pass = false;
  encoding.settings.x264_params = "keyint=10:min-keyint=10:scenecut=0:bframes=0:ref=1";
  encode::encodeDataset(rendered().raw, video, encoding);
  test::damagePacket(video / "mav0" / "cam1" / "data.mp4", 18);

  const pipeline::VoRunResult result = pipeline::runVisualOdometry(quietRun(video, dir / "traj.txt", 1));
  REQUIRE_FALSE(result.pipeline_report.error);
  std::vector<std::int64_t> skipped;
  for (const auto& frame : result.pipeline_report.released) {
    if (frame.reason == pipeline::ReleaseReason::kDamaged) skipped.push_back(frame.frame_index);
  }
  // Frame 18 (damaged) and 19 (predicted from it); frame 20 is an I-picture again.
  CHECK(skipped == std::vector<std::int64_t>{18, 19});
  CHECK(result.frames == 38);
  // The frame after the gap knows it follows one, and the run keeps tracking.
  bool gap_seen = false;
  for (const pipeline::FrameRecord& row : result.rows) gap_seen |= row.frame_index == 20 && row.missing_before == 2;
  CHECK(gap_seen);
  CHECK(result.backend.resets == 0);
  REQUIRE(result.eval.has_value());
  CHECK(result.eval->ate.stats.rmse < 0.05);
}

TEST_CASE("pipeline e2e: an unreadable image in a raw dataset is skipped as damaged; --strict stops naming it") {
  test::ScratchDir dir("pipeline-damaged-png");
  const fs::path raw = dir / "raw";
  copyFolder(rendered().raw, raw);
  const fs::path png = openDataset(raw).frames[24].left;
  const std::string bytes = fileText(png);
  std::ofstream(png, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);

  for (const int threads : {1, 0}) {
    INFO("threads " << threads);
    pipeline::VoRunOptions options = quietRun(raw, dir / "traj.txt", threads);
    const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
    REQUIRE_FALSE(result.pipeline_report.error);
    // Counted and listed as the video case counts a frame it cannot decode.
    CHECK(result.pipeline_report.damaged == 1);
    REQUIRE(result.pipeline_report.released.size() == 1);
    CHECK(result.pipeline_report.released.front().frame_index == 24);
    CHECK(result.pipeline_report.released.front().reason == pipeline::ReleaseReason::kDamaged);
    CHECK(result.frames == 39);
    CHECK(countRows(dir / "traj.txt") == 39);
    bool named = false;
    for (const std::string& warning : result.warnings) named |= warning.find(png.string()) != std::string::npos;
    CHECK(named);
    bool gap_seen = false;
    for (const pipeline::FrameRecord& row : result.rows) gap_seen |= row.missing_before > 0;
    CHECK(gap_seen);
    CHECK(result.backend.resets == 0);
  }

  // Through the command line: a warning naming the file and exit 0; with --strict an error and exit 1.
  const std::string run = "run " + raw.string() + " --threads 1 -o " + (dir / "cli.txt").string();
  const test::CommandOutput skipped = test::runVocaOutput(run);
  INFO(skipped.text);
  CHECK(skipped.exit_code == 0);
  CHECK(skipped.text.find("warning: frame 24 skipped as damaged: " + png.string()) != std::string::npos);
  CHECK(skipped.text.find("1 damaged: 24(damaged)") != std::string::npos);
  const test::CommandOutput strict = test::runVocaOutput(run + " --strict");
  INFO(strict.text);
  CHECK(strict.exit_code == 1);
  CHECK(strict.text.find("voca run: error: read stage failed: frame 24 is damaged: " + png.string()) !=
        std::string::npos);
  CHECK(countRows(dir / "cli.txt") == 24);
}

TEST_CASE("pipeline e2e: a failure with few right-camera points hints at stereo_max_recovered_dist2_px2, once") {
  // At 60 kbit/s the two cameras' streams differ so much that almost no stereo match passes its round
  // trip, and the estimator finds too few stereo points.
  test::ScratchDir dir("pipeline-stereo-hint");
  const std::string run =
      "run " + rendered().raw.string() + " --encode 60k --mode none --threads 1 -o " + (dir / "traj.txt").string();
  const test::CommandOutput plain = test::runVocaOutput(run);
  INFO(plain.text);
  REQUIRE(plain.exit_code == 0);
  const std::size_t hint = plain.text.find("hint: the right camera holds ");
  CHECK(hint != std::string::npos);
  CHECK(plain.text.find("\"stereo_max_recovered_dist2_px2\"", hint) != std::string::npos);
  CHECK(plain.text.find("hint: the right camera", hint + 1) == std::string::npos);
  // A config whose stereo round trip is already as loose as the hint says gets none.
  const fs::path config = dir / "stereo.json";
  std::ofstream(config) << R"({"frontend": {"stereo_max_recovered_dist2_px2": 1.0}})";
  const test::CommandOutput loose = test::runVocaOutput(run + " --config " + config.string());
  INFO(loose.text);
  CHECK(loose.exit_code == 0);
  CHECK(loose.text.find("hint: the right camera") == std::string::npos);
}

TEST_CASE("pipeline e2e: a run that estimates no pose is an error naming the likeliest cause; its files stay") {
  test::ScratchDir dir("pipeline-no-estimate");
  const fs::path trajectory = dir / "traj.txt";
  const std::string run = "run " + rendered().video.string() + " --threads 1 -o " + trajectory.string();
  // A detection border that leaves no cell: no corner anywhere, every frame lost.
  const fs::path config = dir / "border.json";
  std::ofstream(config) << R"({"frontend": {"detection_border_px": 300}})";
  const test::CommandOutput no_cells = test::runVocaOutput(run + " --config " + config.string());
  INFO(no_cells.text);
  CHECK(no_cells.exit_code == 1);
  CHECK(no_cells.text.find("error: no pose was estimated: all 40 frames were lost") != std::string::npos);
  CHECK(no_cells.text.find("hold 0 grid cells for corners") != std::string::npos);
  CHECK(fs::exists(trajectory));
  // Its rows hold the start pose, not estimates: no ATE or RTE over them.
  CHECK(no_cells.text.find("not evaluated (no pose was estimated)") != std::string::npos);
  CHECK(no_cells.text.find("ATE: ") == std::string::npos);
  CHECK(no_cells.text.find("RTE (") == std::string::npos);
  // A tracker too small for the estimator: the option is named, not the calibration.
  const test::CommandOutput one_point = test::runVocaOutput(run + " --max-points 1");
  INFO(one_point.text);
  CHECK(one_point.exit_code == 1);
  CHECK(one_point.text.find("error: no pose was estimated") != std::string::npos);
  CHECK(one_point.text.find("keeps at most 1 point per camera (--max-points), fewer than the 12 a frame needs") !=
        std::string::npos);
  CHECK(one_point.text.find("Check the calibration") == std::string::npos);
  // Too few points for another reason (12 kept, fewer of them matched in both cameras): the generic hint.
  const test::CommandOutput few_points = test::runVocaOutput(run + " --max-points 12");
  INFO(few_points.text);
  CHECK(few_points.exit_code == 1);
  CHECK(few_points.text.find("error: no pose was estimated") != std::string::npos);
  CHECK(few_points.text.find("Check the calibration") != std::string::npos);
  // The same video with the default settings estimates its poses: no error.
  const test::CommandOutput normal = test::runVocaOutput(run);
  CHECK(normal.exit_code == 0);
  CHECK(normal.text.find("no pose was estimated") == std::string::npos);
  CHECK(normal.text.find("ATE: ") != std::string::npos);
}

TEST_CASE("pipeline e2e: a run too short to evaluate says so once, naming its ground truth") {
  test::ScratchDir dir("pipeline-too-short");
  const test::CommandOutput two = test::runVocaOutput("run " + rendered().video.string() +
                                                      " --frames 2 --threads 1 -o " + (dir / "traj.txt").string());
  INFO(two.text);
  CHECK(two.exit_code == 0);
  CHECK(two.text.find("warning: cannot evaluate against") != std::string::npos);
  CHECK(two.text.find("data.csv, not evaluated (see the warning)") != std::string::npos);
  CHECK(two.text.find("no ground truth with the dataset") == std::string::npos);
}

TEST_CASE("pipeline e2e: a failure where the tracker lost most points hints at retry_previous_flow, once") {
  // Twelve frames cut out of the fast sequence: the image jumps far beyond the pyramid's reach.
  test::ScratchDir dir("pipeline-jump");
  const fs::path raw = dir / "raw";
  copyFolder(rendered().raw, raw);
  for (const char* cam : {"cam0", "cam1"}) {
    const fs::path csv = raw / "mav0" / cam / "data.csv";
    std::istringstream in(fileText(csv));
    std::ofstream out(csv, std::ios::trunc);
    int row = 0;
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line[0] != '#' && row++ >= 20 && row <= 32) continue;
      out << line << '\n';
    }
  }
  // The shipped files retry raw frames; the hint is for a config that does not.
  const fs::path off = dir / "off.json";
  std::ofstream(off) << R"({"frontend": {"retry_previous_flow": "off"}})";
  const std::string run = "run " + raw.string() + " --mode none --threads 1 -o " + (dir / "traj.txt").string();
  const test::CommandOutput plain = test::runVocaOutput(run + " --config " + off.string());
  INFO(plain.text);
  REQUIRE(plain.exit_code == 0);
  REQUIRE(plain.text.find("reset (too few inliers)") != std::string::npos);
  const std::size_t hint = plain.text.find("hint: the tracker lost ");
  CHECK(hint != std::string::npos);
  CHECK(plain.text.find("\"retry_previous_flow\": \"always\"", hint) != std::string::npos);
  CHECK(plain.text.find("hint: ", hint + 1) == std::string::npos);
  // With the key acting on this input there is nothing to suggest: "raw" (these frames are raw), as
  // in the shipped file the run picks without --config.
  const fs::path config = dir / "retry.json";
  std::ofstream(config) << R"({"frontend": {"retry_previous_flow": "raw"}})";
  for (const std::string& options : {" --config " + config.string(), std::string()}) {
    const test::CommandOutput retried = test::runVocaOutput(run + options);
    INFO(retried.text);
    CHECK(retried.exit_code == 0);
    CHECK(retried.text.find("hint: ") == std::string::npos);
  }
}

TEST_CASE("pipeline e2e: a source that fails or ends early leaves a clean result") {
  const Dataset dataset = openDataset(rendered().video);
  const StereoRig rig = loadCalibration(*dataset.calibration);
  test::ScratchDir dir("pipeline-faulty-source");
  for (const int threads : {1, 0}) {
    INFO("threads " << threads);
    FaultySource failing(openDatasetSource(dataset), 17, -1);
    pipeline::VoRunOptions options = quietRun({}, dir / "failing.txt", threads);
    const pipeline::VoRunResult failed = pipeline::runVisualOdometryOn(failing, rig, VocaConfig{}, options);
    REQUIRE(failed.pipeline_report.error);
    CHECK(failed.pipeline_report.error->stage == "read");
    CHECK(failed.pipeline_report.error->message.find("device disappeared") != std::string::npos);
    CHECK(failed.frames == 17);
    CHECK(countRows(dir / "failing.txt") == 17);

    FaultySource ending(openDatasetSource(dataset), -1, 12);
    options.trajectory_file = dir / "ending.txt";
    const pipeline::VoRunResult ended = pipeline::runVisualOdometryOn(ending, rig, VocaConfig{}, options);
    CHECK_FALSE(ended.pipeline_report.error);
    CHECK(ended.frames == 12);
    CHECK(loadTrajectory(dir / "ending.txt").poses.size() == 12);
  }
}

TEST_CASE("pipeline e2e: SIGINT, SIGTERM and SIGHUP stop voca run cleanly; a second signal exits at once") {
  test::ScratchDir dir("pipeline-signals");
  const fs::path tmp = dir / "tmp";
  fs::create_directories(tmp);
  struct Case {
    int signal;
    int expected_exit;
  };
  for (const Case c : {Case{SIGINT, 130}, Case{SIGTERM, 143}, Case{SIGHUP, 129}}) {
    INFO("signal " << c.signal);
    const fs::path trajectory = dir / ("traj_" + std::to_string(c.signal) + ".txt");
    const fs::path log = dir / ("log_" + std::to_string(c.signal) + ".txt");
    // --encode makes a temporary folder; --realtime paces the 2 s sequence so the signal lands mid-run.
    const pid_t pid = test::spawnVoca("run " + rendered().raw.string() + " --encode 500k --realtime --out " +
                                          trajectory.string() + " --stats " + (dir / "stats.json").string(),
                                      tmp, log);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (countRows(trajectory) < 5 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    REQUIRE(countRows(trajectory) >= 5);
    kill(pid, c.signal);
    int status = 0;
    REQUIRE(waitpid(pid, &status, 0) == pid);
    INFO(fileText(log));
    REQUIRE(WIFEXITED(status));
    CHECK(WEXITSTATUS(status) == c.expected_exit);
    // Every frame estimated before the stop is in the file, and it parses.
    const Trajectory written = loadTrajectory(trajectory);
    CHECK(written.poses.size() < 40);
    CHECK(fileText(log).find("after " + std::to_string(written.poses.size()) + " frames") != std::string::npos);
    CHECK(fs::exists(dir / "stats.json"));
    CHECK(fs::is_empty(tmp));  // the encoded temporary folder is gone
  }
  // A second signal ends the process at once, whatever it was doing.
  const pid_t pid = test::spawnVoca(
      "run " + rendered().raw.string() + " --encode 500k --realtime --out " + (dir / "twice.txt").string(), tmp,
      dir / "twice.log");
  // Signal only once the handlers are in place (they are installed before --encode makes its
  // temporary folder); a fixed delay raced the process start on a loaded machine.
  const auto started_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (fs::is_empty(tmp) && std::chrono::steady_clock::now() < started_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  REQUIRE_FALSE(fs::is_empty(tmp));
  kill(pid, SIGINT);
  kill(pid, SIGINT);
  int status = 0;
  REQUIRE(waitpid(pid, &status, 0) == pid);
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 130);
}

TEST_CASE("pipeline e2e: options that do nothing for the input are named in warnings") {
  test::ScratchDir dir("pipeline-ignored-options");
  const auto warningsOf = [&](const fs::path& input, const std::function<void(pipeline::VoRunOptions&)>& set) {
    pipeline::VoRunOptions options = quietRun(input, dir / "traj.txt", 1);
    options.max_frames = 3;
    set(options);
    const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
    std::string all;
    for (const std::string& warning : result.warnings) all += warning + "\n";
    return all;
  };
  const std::string images = warningsOf(rendered().raw, [](pipeline::VoRunOptions& o) {
    o.speed = 2.0;
    o.stream_timeout_s = 5.0;
    o.decoder = decode::DecoderKind::kSoftware;
  });
  CHECK(images.find("--speed 2 has no effect without --realtime") != std::string::npos);
  CHECK(images.find("--stream-wait and --stream-timeout apply to stream URLs only") != std::string::npos);
  CHECK(images.find("--decoder and --skip-deblock apply to video") != std::string::npos);
  const std::string video =
      warningsOf(rendered().video, [](pipeline::VoRunOptions& o) { o.encode_bitrate_bps = 500000; });
  CHECK(video.find("is encoded video already; it was replayed as it is") != std::string::npos);
  // Options that act say nothing.
  const std::string acting = warningsOf(rendered().video, [](pipeline::VoRunOptions& o) {
    o.realtime = true;
    o.speed = 4.0;
    o.decoder = decode::DecoderKind::kSoftware;
  });
  CHECK(acting.empty());
}

TEST_CASE("pipeline e2e: live-rate replay from a later frame does not wait through the frames before it") {
  // A video is decoded from its start for the references; those frames come at once, and the
  // recording's clock starts at the first tracked frame (20 Hz: frames 30..34 are due 0.2 s later).
  const Dataset dataset = openDataset(rendered().video);
  const std::unique_ptr<StereoSource> source = openDatasetSource(dataset, {.first_frame = 30});
  pipeline::SourceStageAdapter read(*source, {.realtime = true});
  pipeline::FrameSlot slot;
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::int64_t> arrivals;
  for (int i = 0; i < 35; ++i) {
    REQUIRE(read.produce(slot) == pipeline::Produced::kFrame);
    CHECK(slot.frame.frame_index == i);
    if (i >= 30) arrivals.push_back(slot.arrival_ns);
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(seconds >= 0.19);
  CHECK(seconds < 1.0);  // the 30 frames before the start would take 1.5 s paced
  for (std::size_t i = 1; i < arrivals.size(); ++i) {
    CHECK(arrivals[i] - arrivals[0] ==
          dataset.frames[30 + i].t_ns - dataset.frames[30].t_ns);  // due at the recording's own intervals
  }
}

TEST_CASE("pipeline e2e: --format kitti writes the left camera's poses, which voca eval reads as such") {
  test::ScratchDir dir("pipeline-kitti-format");
  const std::string run = "run " + rendered().video.string() + " --threads 1 --mode none";
  const fs::path tum = dir / "traj.tum", kitti = dir / "traj.kitti";
  REQUIRE(test::runVoca(run + " -o " + tum.string()) == 0);
  REQUIRE(test::runVoca(run + " --format kitti -o " + kitti.string()) == 0);
  const Trajectory body = loadTrajectory(tum, TrajectoryFormat::kTum);
  const Trajectory cam0 = loadTrajectory(kitti, TrajectoryFormat::kKitti);
  REQUIRE(body.poses.size() == cam0.poses.size());
  REQUIRE(body.poses.size() > 30);
  // The rendered rig's body is EuRoC's IMU, half a turn and a few centimetres from cam0.
  const SE3d T_body_cam0 = loadCalibration(rendered().video / "calib.json").cameras[0].T_body_cam;
  REQUIRE(T_body_cam0.translation().norm() > 0.01);
  for (std::size_t i = 0; i < body.poses.size(); ++i) {
    const SE3d expected = body.poses[i].T_world_body * T_body_cam0;
    CHECK((cam0.poses[i].T_world_body.translation() - expected.translation()).norm() < 1e-6);
    CHECK((cam0.poses[i].T_world_body.so3().inverse() * expected.so3()).log().norm() < 1e-6);
  }

  // Evaluated as a KITTI file with the run's times and the calibration, it gives the TUM file's errors.
  const fs::path times = dir / "times.txt";
  {
    std::ofstream out(times);
    out.precision(17);
    for (const TimedPose& pose : body.poses) out << static_cast<double>(pose.t_ns) * 1e-9 << '\n';
  }
  const fs::path gt = rendered().video / "mav0" / "state_groundtruth_estimate0" / "data.csv";
  const auto ateOf = [&](const std::string& args) {
    const test::CommandOutput eval = test::runVocaOutput("eval --gt " + gt.string() + " " + args);
    INFO(eval.text);
    REQUIRE(eval.exit_code == 0);
    const std::size_t row = eval.text.find("ATE (se3 aligned)");
    REQUIRE(row != std::string::npos);
    return std::stod(eval.text.substr(row + std::string("ATE (se3 aligned)").size()));
  };
  const double from_tum = ateOf("--est " + tum.string());
  const double from_kitti = ateOf("--est " + kitti.string() + " --est-times " + times.string() + " --calib " +
                                  (rendered().video / "calib.json").string());
  CHECK(from_tum > 0.0);
  CHECK(from_kitti == doctest::Approx(from_tum).epsilon(1e-3));
}

TEST_CASE("pipeline e2e: a signal stops voca encode cleanly and leaves an earlier encoding as it was") {
  test::ScratchDir dir("encode-signal");
  const fs::path out = dir / "out";
  const std::string encode = "encode " + rendered().raw.string() + " -o " + out.string();
  REQUIRE(test::runVoca(encode) == 0);
  const auto snapshot = [&] {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(out)) {
      if (entry.is_regular_file()) files[fs::relative(entry.path(), out).string()] = fileText(entry.path());
    }
    return files;
  };
  const auto before = snapshot();
  REQUIRE(before.count("mav0/cam1/data.mp4") == 1);

  // Another rate, so a replaced file would differ. The staged video appears once the encoding runs
  // (the handlers are installed before), so the signal lands mid-encoding.
  const fs::path log = dir / "log.txt";
  const pid_t pid = test::spawnVoca(encode + " --bitrate 800k", dir.path(), log);
  REQUIRE(test::signalWhenWritten(pid, out / "mav0" / "cam0" / "data.partial.mp4", SIGINT));
  const int exit_code = test::waitExitCode(pid);
  INFO(fileText(log));
  CHECK(exit_code == 130);
  CHECK(fileText(log).find("stopped by a signal before the encoding finished; nothing was written") !=
        std::string::npos);
  CHECK(snapshot() == before);  // same files, same bytes, no temporary file left
}

TEST_CASE("pipeline e2e: live-rate replay paces the input and reports latency; outputs are written") {
  test::ScratchDir dir("pipeline-realtime");
  pipeline::VoRunOptions options = quietRun(rendered().video, dir / "traj.txt", 0);
  options.realtime = true;
  options.statistics_file = dir / "stats.json";
  options.pipeline_options.trace_path = dir / "trace.json";
  options.trajectory_format = TrajectoryFormat::kKitti;
  const auto start = std::chrono::steady_clock::now();
  const pipeline::VoRunResult result = pipeline::runVisualOdometry(options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  REQUIRE_FALSE(result.pipeline_report.error);
  // 40 frames at 20 Hz: 39 intervals of 50 ms.
  CHECK(seconds >= 1.9);
  CHECK(result.pipeline_report.completed + result.pipeline_report.dropped == 40);
  CHECK(result.pipeline_report.end_to_end.count() == result.pipeline_report.completed);
  // The source's wait for each frame's due time is the recording's rate, not the source's work: its
  // service time is the read alone, far below the 50 ms between frames.
  REQUIRE(!result.pipeline_report.stages.empty());
  CHECK(result.pipeline_report.stages.front().service.quantileNs(0.5) < 10'000'000);
  // KITTI rows: 12 numbers, one row per estimated frame.
  const Trajectory kitti = loadTrajectory(dir / "traj.txt", TrajectoryFormat::kKitti);
  CHECK(kitti.poses.size() == static_cast<std::size_t>(result.frames));
  const std::string stats = fileText(dir / "stats.json");
  CHECK(stats.find("\"frame_rows\"") != std::string::npos);
  CHECK(stats.find("\"end_to_end\"") != std::string::npos);
  CHECK(fs::file_size(dir / "trace.json") > 1000);
}

// The whole pipeline in steady state allocates nothing per frame in our code: every stage is wrapped
// in a counter of heap allocations, with malloc itself interposed (so FFmpeg's av_malloc is seen too,
// not only operator new). FFmpeg allocates a few buffers per frame inside the demuxer and decoder;
// the test states how many and why, and requires exactly those and nothing more.

#include <doctest/doctest.h>
#include <link.h>
#include <malloc.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <new>

#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "drivers/source/dataset_source.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "pipeline/runtime/runner.h"
#include "pipeline/sinks/statistics_sink.h"
#include "pipeline/sinks/trajectory_sink.h"
#include "pipeline/stages/decode_stage.h"
#include "pipeline/stages/estimation_stages.h"
#include "pipeline/stages/source_stage.h"
#include "pipeline/vo/vo_runner.h"
#include "tests/test_frontend_support.h"
#include "tests/test_support.h"

// ---- every heap allocation of the process, C and C++, by who asked ---------------------------
// malloc and friends are interposed here; each call is attributed by its return address to FFmpeg
// (the libav*/libsw* libraries) or to everything else (our code, the C++ library, libc).

namespace {
std::atomic<long> g_allocations{0};
std::atomic<long> g_ffmpeg_allocations{0};
// Address ranges of FFmpeg's libraries, filled once before anything is measured.
struct Range {
  std::uintptr_t begin, end;
};
std::array<Range, 64> g_ffmpeg_ranges{};
std::atomic<int> g_num_ranges{0};

void countAllocation(const void* caller) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const auto address = reinterpret_cast<std::uintptr_t>(caller);
  for (int i = 0, n = g_num_ranges.load(std::memory_order_acquire); i < n; ++i) {
    if (address >= g_ffmpeg_ranges[static_cast<std::size_t>(i)].begin &&
        address < g_ffmpeg_ranges[static_cast<std::size_t>(i)].end) {
      g_ffmpeg_allocations.fetch_add(1, std::memory_order_relaxed);
      return;
    }
  }
}

int collectFfmpegRanges(dl_phdr_info* info, std::size_t /*size*/, void* /*data*/) {
  const std::string_view name = info->dlpi_name == nullptr ? "" : info->dlpi_name;
  if (name.find("/libav") == std::string_view::npos && name.find("/libsw") == std::string_view::npos) return 0;
  for (int i = 0; i < info->dlpi_phnum; ++i) {
    const ElfW(Phdr)& segment = info->dlpi_phdr[i];
    if (segment.p_type != PT_LOAD || (segment.p_flags & PF_X) == 0) continue;
    const int n = g_num_ranges.load();
    if (n == static_cast<int>(g_ffmpeg_ranges.size())) return 0;
    const std::uintptr_t begin = info->dlpi_addr + segment.p_vaddr;
    g_ffmpeg_ranges[static_cast<std::size_t>(n)] = {begin, begin + segment.p_memsz};
    g_num_ranges.store(n + 1, std::memory_order_release);
  }
  return 0;
}
}  // namespace

// The project builds with hidden visibility; these must stay exported or the FFmpeg libraries keep
// calling libc's malloc and their allocations go uncounted.
#pragma GCC visibility push(default)
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);

void* malloc(std::size_t size) {
  countAllocation(__builtin_return_address(0));
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  countAllocation(__builtin_return_address(0));
  return __libc_calloc(count, size);
}
void* realloc(void* p, std::size_t size) {
  countAllocation(__builtin_return_address(0));
  return __libc_realloc(p, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  countAllocation(__builtin_return_address(0));
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  countAllocation(__builtin_return_address(0));
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  countAllocation(__builtin_return_address(0));
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr) return ENOMEM;
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}
#pragma GCC visibility pop

// operator new goes through malloc above (from the C++ library: counted as not FFmpeg's).

using namespace voca;
using namespace voca::pipeline;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 320, kHeight = 240, kFrames = 60, kWarmup = 15;

// Allocations a stage makes itself (not those of the stages it forwards to in the same thread).
struct Tally {
  long steady = 0;  // all allocations from frame kWarmup on
  long ffmpeg = 0;  // of these, made by FFmpeg's libraries
  long frames = 0;  // frames counted
  long ours() const { return steady - ffmpeg; }
};

struct Mark {
  long all = 0, ffmpeg = 0;
  static Mark now() { return {g_allocations.load(), g_ffmpeg_allocations.load()}; }
};

class CountingStage final : public Stage, private Emitter {
 public:
  explicit CountingStage(Stage& inner) : inner_(inner) {}
  std::string_view name() const override { return inner_.name(); }
  bool canSkipInput() const override { return inner_.canSkipInput(); }
  int relativeCost() const override { return inner_.relativeCost(); }
  void start(const StageContext& context) override { inner_.start(context); }
  void process(FrameSlot& slot, Emitter& out) override {
    out_ = &out;
    counting_ = slot.frameIndex() >= kWarmup;
    if (counting_) ++tally.frames;
    mark_ = Mark::now();
    inner_.process(slot, *this);
    pause();
  }
  void finish(Emitter& out) override {
    out_ = &out;
    counting_ = false;
    inner_.finish(*this);
  }
  Tally tally;

 private:
  void pause() {
    if (!counting_) return;
    const Mark now = Mark::now();
    tally.steady += now.all - mark_.all;
    tally.ffmpeg += now.ffmpeg - mark_.ffmpeg;
  }
  void forward(FrameSlot& slot) override {
    pause();
    out_->forward(slot);
    mark_ = Mark::now();
  }
  void release(FrameSlot& slot, ReleaseReason reason) override {
    pause();
    out_->release(slot, reason);
    mark_ = Mark::now();
  }
  Stage& inner_;
  Emitter* out_ = nullptr;
  bool counting_ = false;
  Mark mark_;
};

class CountingSource final : public SourceStage {
 public:
  explicit CountingSource(SourceStage& inner) : inner_(inner) {}
  std::string_view name() const override { return inner_.name(); }
  Produced produce(FrameSlot& slot) override {
    const Mark mark = Mark::now();
    const Produced produced = inner_.produce(slot);
    if (produced == Produced::kFrame && slot.frameIndex() >= kWarmup) {
      const Mark now = Mark::now();
      tally.steady += now.all - mark.all;
      tally.ffmpeg += now.ffmpeg - mark.ffmpeg;
      ++tally.frames;
    }
    return produced;
  }
  Tally tally;

 private:
  SourceStage& inner_;
};

// Counts the whole process's allocations between two frames reaching the end of the pipeline.
class WindowSink final : public FrameSink {
 public:
  void consume(const FrameSlot& slot) override {
    if (slot.frameIndex() == kWarmup) start_ = Mark::now();
    if (slot.frameIndex() == kFrames - 1) {
      const Mark now = Mark::now();
      total = now.all - start_.all;
      ffmpeg = now.ffmpeg - start_.ffmpeg;
    }
  }
  long total = -1, ffmpeg = -1;

 private:
  Mark start_;
};

// A VOCA video folder of a textured plane moving 3 px right and 1 px down per frame (keyframe every
// 20 frames, so I-frames and bridging happen inside the counted frames), with its calibration.
fs::path makeVideoFolder(const test::ScratchDir& dir) {
  const fs::path mav0 = dir / "seq" / "mav0";
  const test::WaveTexture texture(11);
  encode::EncoderSettings settings;
  settings.two_pass = false;
  settings.x264_params += ":keyint=20:min-keyint=20";
  for (int c = 0; c < 2; ++c) {
    fs::create_directories(mav0 / ("cam" + std::to_string(c)));
    encode::encodeVideoFile(mav0 / ("cam" + std::to_string(c)) / "data.mp4", settings,
                            [&](const std::function<void(GrayView)>& emit) {
                              GrayImage image;
                              for (int k = 0; k < kFrames; ++k) {
                                texture.render(image, kWidth, kHeight, 3.0 * k - (c == 1 ? 12.0 : 0.0), 1.0 * k);
                                emit(image.view());
                              }
                            });
    std::ofstream csv(mav0 / ("cam" + std::to_string(c)) / "data.csv");
    csv << "#timestamp [ns],filename\n";
    for (int k = 0; k < kFrames; ++k) csv << 1000000000LL + 50000000LL * k << "," << k << ".png\n";
  }
  saveBasaltCalibration(test::pinholeRig(kWidth, kHeight, 300.0, 0.11), dir / "seq" / "calib.json");
  return dir / "seq";
}

}  // namespace

TEST_CASE("pipeline: steady state allocates only what FFmpeg allocates per frame, in one thread or many") {
  test::ScratchDir dir("pipeline-alloc");
  const fs::path folder = makeVideoFolder(dir);
  const Dataset dataset = openDataset(folder);
  const StereoRig rig = loadCalibration(*dataset.calibration);
  encode::silenceCodecLogs();
  dl_iterate_phdr(collectFfmpegRanges, nullptr);
  REQUIRE(g_num_ranges.load() >= 3);  // libavcodec, libavformat, libavutil at least
  double read_per_frame = 0.0, decode_per_frame = 0.0;

  // Stage by stage, every stage in this thread.
  {
    VideoFolderSource source(dataset);
    SourceStageAdapter read(source, {});
    DecodeStageOptions decode_options;
    decode_options.decoder.kind = decode::DecoderKind::kSoftware;
    decode_options.decoder.strict = false;
    decode_options.decoder.log_choice = false;
    DecodeStage decode(source.info().streams, decode_options);
    VocaConfig config;
    DepthHintChannel hints;
    FrontendStage frontend(config.frontend, rig, {.max_points = 300}, &hints, true);
    BackendStage backend(config.backend, rig, &hints);
    TrajectorySink trajectory(dir / "traj.txt", TrajectoryFormat::kTum, kFrames, rig.cameras[0].T_body_cam);
    StatisticsSink statistics(kFrames, 1, 2, 3);
    SinkStage write({&trajectory, &statistics});
    CountingSource counted_read(read);
    CountingStage counted_decode(decode), counted_frontend(frontend), counted_backend(backend), counted_write(write);
    PipelineOptions options;
    options.threads = 1;
    options.slot_shape = {kWidth, kHeight, 300};
    Pipeline pipeline(counted_read, {&counted_decode, &counted_frontend, &counted_backend, &counted_write}, options);
    const RunReport report = pipeline.run();
    REQUIRE_FALSE(report.error);
    REQUIRE(report.completed == kFrames);
    // The counter is live: the first frames allocated (buffers sized on first use).
    CHECK(g_allocations.load() > 0);
    const long frames = kFrames - kWarmup;
    CHECK(counted_read.tally.frames == frames);
    const auto perFrame = [&](const Tally& t) { return static_cast<double>(t.ffmpeg) / static_cast<double>(frames); };
    MESSAGE("FFmpeg's allocations per stereo frame in steady state: read "
            << perFrame(counted_read.tally) << ", decode " << perFrame(counted_decode.tally));
    // Our code allocates nothing per frame in any stage, demuxing and decoding included.
    CHECK(counted_read.tally.ours() == 0);
    CHECK(counted_decode.tally.ours() == 0);
    CHECK(counted_frontend.tally.steady == 0);
    CHECK(counted_backend.tally.steady == 0);
    CHECK(counted_write.tally.steady == 0);
    CHECK(statistics.frames() == kFrames);
    // FFmpeg reference-counts every packet and picture: libavformat reads each packet into a new
    // buffer (av_get_packet: the AVBufferRef and its data, plus the demuxer's own bookkeeping), and
    // libavcodec wraps every decoded picture, its references and the exported motion vectors (frame
    // side data; the quantisers too, when prior_max_qp asks for them) in AVBufferRef objects, allocated
    // per frame and freed when the frame is released. Measured with Debian 12's FFmpeg 5.1: 7 per
    // camera and frame in the demuxer, about 40 per camera and frame in the decoder (5 more with the
    // quantisers). The bounds leave 2x for other FFmpeg builds, while a per-macroblock allocation
    // (300 macroblocks per picture here) fails.
    CHECK(counted_read.tally.ffmpeg > 0);
    CHECK(perFrame(counted_read.tally) <= 28.0);
    CHECK(counted_decode.tally.ffmpeg > 0);
    CHECK(perFrame(counted_decode.tally) <= 160.0);
    read_per_frame = perFrame(counted_read.tally);
    decode_per_frame = perFrame(counted_decode.tally);
  }

  // The same through the runner with one thread per stage and the frontend's helper, writing the
  // Chrome trace: the queues, slots, threads and the trace's per-frame events add nothing.
  WindowSink window;
  pipeline::VoRunOptions options;
  options.input = folder;
  options.progress = false;
  options.decoder = decode::DecoderKind::kSoftware;
  options.pipeline_options.threads = 0;
  options.frontend_camera_threads = 2;  // the right camera on the frontend's helper thread
  options.extra_sinks = {&window};
  options.pipeline_options.trace_path = dir / "trace.json";
  VideoFolderSource source(dataset);
  const pipeline::VoRunResult result = runVisualOdometryOn(source, rig, VocaConfig{}, options);
  REQUIRE_FALSE(result.pipeline_report.error);
  REQUIRE(result.frames == kFrames);
  CHECK(result.pipeline_report.threads == 5);
  CHECK(result.frontend_camera_threads == 2);
  // Between frame kWarmup and the last frame leaving the pipeline, all threads together allocated only
  // FFmpeg's share: the queues, slots, threads and sinks add nothing.
  const long window_frames = kFrames - 1 - kWarmup;
  MESSAGE("pipelined: " << window.total << " allocations over " << window_frames << " frames, " << window.ffmpeg
                        << " of them FFmpeg's");
  CHECK(window.total == window.ffmpeg);
  CHECK(result.pipeline_report.stages[2].helper_service.count() == kFrames);  // the trace had helper slices to write
  // Up to a pool's worth of frames (8) may be read and decoded ahead at either end of the window.
  CHECK(static_cast<double>(window.ffmpeg) >= (read_per_frame + decode_per_frame) * (window_frames - 8));
  CHECK(static_cast<double>(window.ffmpeg) <= (read_per_frame + decode_per_frame) * (window_frames + 8));
}

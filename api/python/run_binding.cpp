#include "run_binding.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "conversions.h"
#include "shared_options.h"
#include "voca_rt/voca_rt.h"

namespace voca_python {
namespace {

// voca.run's poses, gathered on the pipeline's output thread: fixed chunks, so a frame copies one
// pose and allocates nothing but once every kChunk frames.
class PoseStore {
 public:
  static constexpr std::size_t kChunk = 4096;

  PoseStore() { chunks_.reserve(256); }

  void add(const voca_rt::Pose& pose) {
    if (size_ % kChunk == 0) chunks_.push_back(std::make_unique<std::array<voca_rt::Pose, kChunk>>());
    (*chunks_.back())[size_ % kChunk] = pose;
    ++size_;
  }

  std::vector<TumValues> tumRows() const {
    std::vector<TumValues> rows;
    rows.reserve(size_);
    for (std::size_t i = 0; i < size_; ++i) rows.push_back(tumValues((*chunks_[i / kChunk])[i % kChunk]));
    return rows;
  }

 private:
  std::vector<std::unique_ptr<std::array<voca_rt::Pose, kChunk>>> chunks_;
  std::size_t size_ = 0;
};

// Runs voca_rt::run on a thread of its own while this one, without the GIL, checks for Ctrl-C every
// 100 ms: a KeyboardInterrupt stops the run as Ctrl-C stops `voca run` (the library's stop request),
// then propagates once the pipeline has stopped cleanly.
voca_rt::Summary runInterruptibly(const voca_rt::Input& input, voca_rt::Options options, PoseStore& store) {
  std::atomic<bool> interrupted{false};
  options.stop_requested = [&interrupted] { return interrupted.load(std::memory_order_relaxed); };
  std::mutex mutex;
  std::condition_variable ended;
  bool done = false;
  voca_rt::Summary summary;
  std::exception_ptr failure;
  std::thread worker([&] {
    try {
      summary = voca_rt::run(input, options, [&store](const voca_rt::Pose& pose) { store.add(pose); });
    } catch (...) {
      failure = std::current_exception();
    }
    std::lock_guard lock(mutex);
    done = true;
    ended.notify_all();
  });
  std::optional<py::error_already_set> interrupt;
  for (;;) {
    {
      py::gil_scoped_release release;
      std::unique_lock lock(mutex);
      if (ended.wait_for(lock, std::chrono::milliseconds(100), [&] { return done; })) break;
    }
    if (!interrupt && PyErr_CheckSignals() != 0) {
      interrupt.emplace();  // takes the pending exception until the run has stopped
      interrupted.store(true, std::memory_order_relaxed);
    }
  }
  worker.join();
  if (interrupt) throw *interrupt;
  if (failure) std::rethrow_exception(failure);
  return summary;
}

py::object runPath(const std::filesystem::path& path, const voca_rt::Options& options, const OptionalPath& ground_truth,
                   const std::optional<std::string>& encode, int max_frames, int first_frame, bool realtime,
                   double speed, double stream_wait_s, double stream_timeout_s, bool return_summary) {
  voca_rt::Input input;
  input.path = path.string();
  input.ground_truth = pathText(ground_truth);
  input.encode_bitrate = encode.value_or("");
  input.max_frames = max_frames;
  input.first_frame = first_frame;
  input.realtime = realtime;
  input.speed = speed;
  input.stream_wait_s = stream_wait_s;
  input.stream_timeout_s = stream_timeout_s;
  PoseStore store;
  const voca_rt::Summary summary = runInterruptibly(input, options, store);
  py::array_t<double> rows = tumArray(store.tumRows());
  // As `voca run` exits 1 on these; what was estimated up to then travels with the error.
  const std::string& why = !summary.error.empty() ? summary.error : summary.failure;
  if (!why.empty()) {
    py::object error = makeError(why, "input");
    error.attr("poses") = rows;
    error.attr("summary") = summaryDict(summary);
    raise(error);
  }
  if (return_summary) return py::make_tuple(rows, summaryDict(summary));
  return rows;
}

constexpr const char* kRunDoc =
    R"doc(Run the odometry over a recorded input, as `voca run <path>` does; returns the poses as a float64
(N, 8) array of TUM rows [t_s, x, y, z, qx, qy, qz, qw], exactly the numbers `voca run --out x.tum`
writes for the same input and options. With return_summary=True: (rows, summary dict), the summary as
Odometry.finish() gives it (with ate_rmse_m and rte_rmse_m when the input has ground truth).

  path              a EuRoC/TUM-VI or KITTI folder (raw images), a VOCA video folder (mav0/camN/data.mp4),
                    a stream URL that `voca stream` sends to (udp://127.0.0.1:5000), or a stream it
                    recorded to a file
  calib             calibration file (default: the one found with the dataset; a stream needs one)
  encode            a raw dataset encoded first at this bitrate ("500k"), as --encode
  max_frames        frames to run (--frames; 0: all); first_frame: the first one (--start-frame)
  gt                ground truth for ATE/RTE (default: the dataset's)
  realtime, speed   replay at the recording's rate times speed, under the live policy (--realtime, --speed)
  stream_wait_s, stream_timeout_s  a stream URL: how long to wait for it to begin; the silence that ends it

Options, as Odometry's and the command line's of the same names (None: the default; mode, config
and threads may also be given by position):
)doc";

constexpr const char* kRunDocEnd = R"doc(
Runs without the GIL; Ctrl-C (KeyboardInterrupt) stops the run cleanly first. Raises voca.Error for
bad input (a missing dataset or calibration, images that do not fit it: the CLI's message) and when a
stage failed or no pose could be estimated; such an error carries .poses (the rows estimated before)
and .summary.)doc";

}  // namespace

void bindRun(py::module_& module) {
  static const std::string run_doc = std::string(kRunDoc) + sharedOptionsDoc() + kRunDocEnd;
  module.def(
      "run",
      [](const std::filesystem::path& path, const OptionalPath& calib, const py::object& mode, const py::object& config,
         const std::optional<std::string>& encode, int max_frames, int first_frame, const py::object& threads,
         const OptionalPath& gt, bool realtime, double speed, double stream_wait_s, double stream_timeout_s,
         bool return_summary, const py::kwargs& shared_options) {
        voca_rt::Options options;
        options.calibration_file = pathText(calib);
        setSharedOption(options, "mode", mode, "voca.run");
        setSharedOption(options, "config", config, "voca.run");
        setSharedOption(options, "threads", threads, "voca.run");
        setSharedOptions(options, shared_options, "voca.run");
        return runPath(path, options, gt, encode, max_frames, first_frame, realtime, speed, stream_wait_s,
                       stream_timeout_s, return_summary);
      },
      py::arg("path"), py::arg("calib") = py::none(), py::arg("mode") = py::none(), py::arg("config") = py::none(),
      py::arg("encode") = py::none(), py::arg("max_frames") = 0, py::arg("first_frame") = 0, py::arg("threads") = 0,
      py::kw_only(), py::arg("gt") = py::none(), py::arg("realtime") = false, py::arg("speed") = 1.0,
      py::arg("stream_wait_s") = 30.0, py::arg("stream_timeout_s") = 3.0, py::arg("return_summary") = false,
      run_doc.c_str());
}

}  // namespace voca_python

// The Python module `voca`: VOCA-RT's library API (voca_rt::) for Python programs and notebooks.
// It uses nothing of the project but the public headers, as any other program of the library would.
//
// Python never runs on a pipeline thread: poses reach Python through poll() (voca.Odometry) or are
// gathered in C++ and converted once the run is over (voca.run). A pose callback taking the GIL on the
// pipeline's output thread would stall the whole pipeline behind whatever Python does meanwhile.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <array>
#include <atomic>
#include <charconv>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "shared_options.h"
#include "voca_rt/voca_rt.h"

namespace py = pybind11;

namespace {

using OptionalPath = std::optional<std::filesystem::path>;
using TumValues = std::array<double, 8>;

// voca.Error, created when the module loads; lives as long as the interpreter.
PyObject* error_type = nullptr;

const char* kindName(voca_rt::Error::Kind kind) { return kind == voca_rt::Error::Kind::kInput ? "input" : "runtime"; }

// A voca.Error instance carrying the library's message unchanged, and what failed ("input":
// unusable input, the CLI's exit code 1; "runtime": a device, codec or the OS).
py::object makeError(const std::string& message, const char* kind) {
  py::object error = py::reinterpret_borrow<py::object>(error_type)(message);
  error.attr("kind") = kind;
  return error;
}

[[noreturn]] void raise(const py::object& error) {
  PyErr_SetObject(error_type, error.ptr());
  throw py::error_already_set();
}

[[noreturn]] void raiseInputError(const std::string& message) { raise(makeError(message, "input")); }

std::string pathText(const OptionalPath& path) { return path ? path->string() : std::string(); }

// The eight numbers of the TUM row `voca run --out` writes for the pose, read back from the very text
// voca_rt::tumRow formats: the time as its nine-decimal seconds read as a double (a nanosecond count
// of today's epoch exceeds 2^53, so t_ns / 1e9 could differ in the last bit), and the shortest exact
// forms of the pose's numbers. Equal to parsing the CLI's file, bit for bit.
TumValues tumValues(const voca_rt::Pose& pose) {
  const std::string row = voca_rt::tumRow(pose);
  TumValues values{};
  const char* at = row.data();
  const char* const end = row.data() + row.size();
  for (double& value : values) {
    while (at < end && *at == ' ') ++at;
    const std::from_chars_result read = std::from_chars(at, end, value);
    if (read.ec != std::errc()) throw std::logic_error("voca_rt::tumRow wrote a row that does not read back: " + row);
    at = read.ptr;
  }
  return values;
}

py::array_t<double> tumArray(const std::vector<TumValues>& rows) {
  py::array_t<double> array({static_cast<py::ssize_t>(rows.size()), py::ssize_t{8}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (std::size_t j = 0; j < 8; ++j) out(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(j)) = rows[i][j];
  }
  return array;
}

template <std::size_t N>
py::array_t<double> vectorArray(const std::array<double, N>& values) {
  py::array_t<double> array(static_cast<py::ssize_t>(N));
  std::copy(values.begin(), values.end(), array.mutable_data());
  return array;
}

const char* stateName(voca_rt::TrackingState state) {
  switch (state) {
    case voca_rt::TrackingState::kOk:
      return "ok";
    case voca_rt::TrackingState::kReset:
      return "reset";
    case voca_rt::TrackingState::kLost:
      return "lost";
  }
  return "lost";
}

py::dict latencyDict(const voca_rt::StageLatency& latency) {
  py::dict d;
  d["encode_ms"] = latency.encode_ms;
  d["decode_ms"] = latency.decode_ms;
  d["frontend_ms"] = latency.frontend_ms;
  d["backend_ms"] = latency.backend_ms;
  d["end_to_end_ms"] = latency.end_to_end_ms;
  return d;
}

py::object optionalNumber(const std::optional<double>& value) {
  return value ? py::object(py::float_(*value)) : py::object(py::none());
}

py::dict summaryDict(const voca_rt::Summary& s) {
  py::dict d;
  d["input"] = s.input;
  d["config"] = s.config;
  d["started"] = s.started;
  d["frames"] = s.frames;
  d["keyframes"] = s.keyframes;
  d["resets"] = s.resets;
  d["lost"] = s.lost;
  d["dropped"] = s.dropped;
  d["damaged"] = s.damaged;
  d["frames_lost"] = s.frames_lost;
  d["unpaired"] = s.unpaired;
  d["threads"] = s.threads;
  d["wall_s"] = s.wall_s;
  d["fps"] = s.frames_per_second;
  py::dict end_to_end;
  end_to_end["p50"] = s.end_to_end_ms[0];
  end_to_end["p90"] = s.end_to_end_ms[1];
  end_to_end["p99"] = s.end_to_end_ms[2];
  end_to_end["max"] = s.end_to_end_ms[3];
  d["end_to_end_ms"] = end_to_end;
  d["ate_rmse_m"] = optionalNumber(s.ate_rmse_m);
  d["rte_rmse_m"] = optionalNumber(s.rte_rmse_m);
  d["stopped"] = s.stopped;
  d["error"] = s.error;
  d["failure"] = s.failure;
  d["warnings"] = s.warnings;
  d["report"] = s.report;
  d["latency_report"] = s.latency_report;
  return d;
}

// A contiguous byte view of any object with the buffer protocol (bytes, bytearray, memoryview, a
// uint8 NumPy array), held for as long as the C++ side reads it.
class ByteView {
 public:
  ByteView(const py::handle& object, const char* name) {
    if (PyObject_GetBuffer(object.ptr(), &view_, PyBUF_C_CONTIGUOUS) != 0) {
      PyErr_Clear();
      throw py::type_error(std::string(name) + ": expected bytes (one H.264 access unit), got " +
                           std::string(py::str(py::type::handle_of(object).attr("__name__"))));
    }
  }
  ~ByteView() { PyBuffer_Release(&view_); }
  ByteView(const ByteView&) = delete;
  ByteView& operator=(const ByteView&) = delete;
  const std::uint8_t* data() const { return static_cast<const std::uint8_t*>(view_.buf); }
  std::size_t size() const { return static_cast<std::size_t>(view_.len); }

 private:
  Py_buffer view_{};
};

using GrayArray = py::array_t<std::uint8_t, py::array::c_style>;

// An 8-bit gray image as the library reads it: rows of `width` pixels, pixels adjacent. C-contiguous
// uint8 arrays (what PIL, imageio and OpenCV give) are used as they are; other layouts are copied.
GrayArray grayImage(const py::array& image, const char* name) {
  if (image.dtype().kind() != 'u' || image.itemsize() != 1) {
    raiseInputError(std::string(name) + ": expected an 8-bit gray image (NumPy dtype uint8), got dtype " +
                    std::string(py::str(image.dtype())));
  }
  if (image.ndim() != 2) {
    raiseInputError(std::string(name) + ": expected a gray image of shape (height, width), got " +
                    std::to_string(image.ndim()) + " dimensions");
  }
  GrayArray pixels = GrayArray::ensure(image);
  if (!pixels) throw py::error_already_set();
  return pixels;
}

bool finalizing() { return _Py_IsFinalizing() != 0; }

// voca.Odometry: one voca_rt::Odometry, its pipeline running on threads of its own.
class PyOdometry {
 public:
  explicit PyOdometry(const voca_rt::Options& options) {
    py::gil_scoped_release release;
    odometry_ = std::make_unique<voca_rt::Odometry>(options);
  }

  ~PyOdometry() {
    // Flushing waits for the pipeline, without the GIL so that other Python threads go on; not while
    // the interpreter shuts down, whose thread must keep it.
    if (finalizing() || PyGILState_Check() == 0) {
      odometry_.reset();
      return;
    }
    py::gil_scoped_release release;
    std::lock_guard lock(calls_);
    odometry_.reset();
  }

  PyOdometry(const PyOdometry&) = delete;
  PyOdometry& operator=(const PyOdometry&) = delete;

  bool pushH264(std::int64_t t_ns, const py::object& left, const py::object& right) {
    const ByteView left_bytes(left, "left");
    const ByteView right_bytes(right, "right");
    py::gil_scoped_release release;
    std::lock_guard lock(calls_);
    return odometry_->pushH264(t_ns, left_bytes.data(), left_bytes.size(), right_bytes.data(), right_bytes.size());
  }

  bool pushGray(std::int64_t t_ns, const py::array& left, const py::array& right) {
    const GrayArray left_image = grayImage(left, "left");
    const GrayArray right_image = grayImage(right, "right");
    if (left_image.shape(0) != right_image.shape(0) || left_image.shape(1) != right_image.shape(1)) {
      raiseInputError("push_gray: the left image is " + std::to_string(left_image.shape(1)) + "x" +
                      std::to_string(left_image.shape(0)) + " and the right " + std::to_string(right_image.shape(1)) +
                      "x" + std::to_string(right_image.shape(0)) + "; both cameras give images of one size");
    }
    const int width = static_cast<int>(left_image.shape(1));
    const int height = static_cast<int>(left_image.shape(0));
    py::gil_scoped_release release;
    std::lock_guard lock(calls_);
    return odometry_->pushGray(t_ns, left_image.data(), right_image.data(), width, height);
  }

  py::object poll() {
    voca_rt::Pose pose;
    if (!odometry_->poll(pose)) return py::none();
    return py::cast(pose);
  }

  py::array_t<double> poses() {
    std::vector<TumValues> rows;
    voca_rt::Pose pose;
    while (odometry_->poll(pose)) rows.push_back(tumValues(pose));
    return tumArray(rows);
  }

  py::dict finish(bool discard) {
    voca_rt::Summary summary;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(calls_);
      summary = odometry_->finish(discard ? voca_rt::Odometry::Stop::kDiscard : voca_rt::Odometry::Stop::kFlush);
    }
    return summaryDict(summary);
  }

  bool running() const { return odometry_->running(); }
  std::string error() const { return odometry_->error(); }
  std::string description() const { return odometry_->description(); }

 private:
  std::unique_ptr<voca_rt::Odometry> odometry_;
  // Pushes and finish() from several Python threads take turns: the library lets one thread push
  // while others poll, and the GIL is released while a push waits for room.
  std::mutex calls_;
};

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

py::dict evaluateFiles(const std::filesystem::path& ground_truth, const std::filesystem::path& estimate) {
  voca_rt::Evaluation evaluation;
  {
    py::gil_scoped_release release;
    evaluation = voca_rt::evaluate(ground_truth.string(), estimate.string());
  }
  py::dict d;
  d["associated"] = evaluation.associated;
  d["ate_rmse_m"] = evaluation.ate_rmse_m;
  d["ate_max_m"] = evaluation.ate_max_m;
  d["rte_rmse_m"] = optionalNumber(evaluation.rte_rmse_m);
  d["divergent"] = evaluation.divergent;
  return d;
}

// voca.VideoFolder: iterates a VOCA video folder's stereo access units.
class PyVideoFolder {
 public:
  explicit PyVideoFolder(const std::filesystem::path& folder) {
    py::gil_scoped_release release;
    reader_ = std::make_unique<voca_rt::VideoFolderReader>(folder.string());
  }

  py::object next() {
    bool read = false;
    {
      py::gil_scoped_release release;
      read = reader_->next(packet_);
    }
    if (!read) throw py::stop_iteration();
    const auto bytes = [](const std::vector<std::uint8_t>& data) {
      return py::bytes(reinterpret_cast<const char*>(data.data()), data.size());
    };
    return py::make_tuple(packet_.t_ns, bytes(packet_.left), bytes(packet_.right));
  }

  int width() const { return reader_->width(); }
  int height() const { return reader_->height(); }
  std::int64_t frames() const { return reader_->frames(); }
  py::object calibrationFile() const {
    const std::string file = reader_->calibrationFile();
    return file.empty() ? py::object(py::none()) : py::object(py::str(file));
  }

 private:
  std::unique_ptr<voca_rt::VideoFolderReader> reader_;
  voca_rt::StereoPacket packet_;
};

constexpr const char* kModuleDoc =
    R"doc(VOCA-RT: causal stereo visual odometry on H.264 video, the codec's motion vectors as tracking priors.

The Python face of the VOCA-RT library (libvoca-rt, headers voca_rt/*.h): the same pipeline and the
same numbers as the `voca` command line.

  voca.run(path, calib=None, ...)      a dataset, video folder or stream -> (N, 8) TUM rows
  voca.evaluate(gt, est)               ATE/RTE of a trajectory file, as `voca eval`
  voca.Odometry(calibration, ...)      push frames (H.264 access units or gray images), poll poses
  voca.VideoFolder(path)               the stereo access units of a VOCA video folder, for push_h264
  voca.Pose                            one estimated pose (time, position, orientation xyzw, state)
  voca.Error                           bad input or a failed run; the message is the CLI's

TUM rows are float64 [t_s, x, y, z, qx, qy, qz, qw]: the body pose T_world_body (the calibration's
body frame; the world is the first frame's body pose), the values `voca run --out x.tum` writes.

  import voca
  rows = voca.run("MH_01_easy/mav0", calib="calib.json", max_frames=200)
  print(voca.evaluate("gt.csv", "traj.tum"))
  with voca.Odometry("calib.json") as odometry:
      for t_ns, left, right in voca.VideoFolder("seq-500k"):
          odometry.push_h264(t_ns, left, right)
          while (pose := odometry.poll()) is not None:
              print(pose.t_ns, pose.position, pose.state)

Threads: the pipeline runs on threads of its own; pushes, finish() and whole runs release the GIL.
No Python code ever runs on a pipeline thread: poses are polled.)doc";

constexpr const char* kOdometryDoc = R"doc(Stereo visual odometry on frames the program pushes.

Odometry(calibration, *, input="h264", live=False, ..., **options) builds the pipeline for frames of
the calibration's image size (every buffer allocated here) and starts its threads. Push one frame at a
time with its sensor time (ns, strictly increasing); each pushed frame gives one pose, in order, which
poll() or poses() hand over on any thread (one thread may push while another polls). finish() ends the
input and returns the run's summary. As a context manager, leaving the with-block finishes (flushing
every pushed frame; discarding the waiting ones when the block raised).

  calibration       calibration file: Basalt JSON, Kalibr YAML, EuRoC sensor.yaml (or its mav0), KITTI calib.txt
  input="h264"      "h264": push_h264 with one Annex B access unit per camera (the compressed path, motion
                    vectors as priors); "gray": push_gray with 8-bit images (raw, or encoded on the device
                    first with encode_bitrate)
  live=False        live policy: a push never waits (a frame without room is dropped, push returns False)
                    and a stage that falls behind drops the oldest frame; False: pushes wait for room and
                    every frame is processed, so the same frames always give the same poses
  encode_bitrate=None  gray input: encode each camera at this bitrate ("1M", "500k") first, as on a device
  encoder="auto"    auto, x264, v4l2m2m, vaapi (with encode_bitrate)
  frame_rate_hz=0.0 the cameras' rate, for the on-device encoder's rate control; 0: 20 Hz
  poll_capacity=4096  poses kept for poll(); beyond, the oldest unpolled are dropped

Options, as voca.run's and the command line's of the same names (None: the default):
)doc";

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

PYBIND11_MODULE(voca, m) {
  m.doc() = kModuleDoc;
  m.attr("__version__") = VOCA_RT_VERSION;

  error_type = PyErr_NewExceptionWithDoc(
      "voca.Error",
      "Bad input or a failed run. str(error) is the message `voca` prints after 'error: ' for the same problem "
      "(naming the file, field, option or frame). error.kind: 'input' (unusable input; the CLI exits 1) or "
      "'runtime' (a device, codec or the operating system failed). Errors of voca.run that end a run also carry "
      "error.poses (the (N, 8) TUM rows estimated before) and error.summary.",
      PyExc_RuntimeError, nullptr);
  if (error_type == nullptr) throw py::error_already_set();
  m.attr("Error") = py::handle(error_type);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const voca_rt::Error& e) {
      const py::object error = makeError(e.what(), kindName(e.kind()));
      PyErr_SetObject(error_type, error.ptr());
    }
  });

  py::class_<voca_rt::Pose>(m, "Pose",
                            "One frame's estimated pose: T_world_body, the calibration's body frame in the world "
                            "frame (the first frame's body pose).")
      .def_readonly("t_ns", &voca_rt::Pose::t_ns, "The frame's sensor time in nanoseconds, as pushed.")
      .def_readonly("frame_index", &voca_rt::Pose::frame_index, "The frame's place among the frames pushed, from 0.")
      .def_property_readonly(
          "position", [](const voca_rt::Pose& p) { return vectorArray(p.position); },
          "Translation in metres, float64 array (3,).")
      .def_property_readonly(
          "orientation", [](const voca_rt::Pose& p) { return vectorArray(p.orientation); },
          "Rotation as a unit quaternion x, y, z, w: float64 array (4,).")
      .def_property_readonly(
          "state", [](const voca_rt::Pose& p) { return stateName(p.state); },
          "'ok' (estimated), 'reset' (tracking restarted from this frame at the last good pose) or 'lost' (no "
          "estimate: the last good pose repeated).")
      .def_readonly("keyframe", &voca_rt::Pose::keyframe, "True when the frame became a keyframe.")
      .def_readonly("landmarks", &voca_rt::Pose::landmarks, "Landmarks alive in the sliding window.")
      .def_readonly("inliers", &voca_rt::Pose::inliers, "This frame's observations of landmarks.")
      .def_property_readonly(
          "latency", [](const voca_rt::Pose& p) { return latencyDict(p.latency); },
          "Milliseconds per stage (encode_ms, decode_ms, frontend_ms, backend_ms; 0 for stages the run lacks) "
          "and end_to_end_ms, from the frame's arrival to its pose (wall clock).")
      .def(
          "matrix",
          [](const voca_rt::Pose& p) {
            py::array_t<double> matrix({4, 4});
            const std::array<double, 16> values = p.matrix();
            std::copy(values.begin(), values.end(), matrix.mutable_data());
            return matrix;
          },
          "T_world_body as a float64 (4, 4) matrix.")
      .def_property_readonly(
          "tum_row", [](const voca_rt::Pose& p) { return vectorArray(tumValues(p)); },
          "The TUM row [t_s, x, y, z, qx, qy, qz, qw] (float64 (8,)), the numbers `voca run --out` writes.")
      .def("__repr__", [](const voca_rt::Pose& p) {
        const TumValues v = tumValues(p);
        return "voca.Pose(frame_index=" + std::to_string(p.frame_index) + ", t_ns=" + std::to_string(p.t_ns) +
               ", position=[" + std::string(py::str(py::float_(v[1]))) + ", " + std::string(py::str(py::float_(v[2]))) +
               ", " + std::string(py::str(py::float_(v[3]))) + "], state='" + stateName(p.state) + "'" +
               (p.keyframe ? ", keyframe" : "") + ")";
      });

  static const std::string odometry_doc =
      std::string(kOdometryDoc) + voca_python::sharedOptionsDoc() +
      "\nRaises voca.Error for a calibration, config or option that cannot be used.";
  py::class_<PyOdometry>(m, "Odometry", odometry_doc.c_str())
      .def(py::init([](const OptionalPath& calibration, const std::string& input, bool live,
                       const std::optional<std::string>& encode_bitrate, const std::string& encoder,
                       double frame_rate_hz, std::size_t poll_capacity, const py::kwargs& shared_options) {
             voca_rt::Options options;
             options.calibration_file = pathText(calibration);
             voca_python::setSharedOptions(options, shared_options, "voca.Odometry");
             if (input == "h264") {
               options.input = voca_rt::InputKind::kH264;
             } else if (input == "gray") {
               options.input = voca_rt::InputKind::kGray;
             } else {
               raiseInputError("input: expected h264 or gray, got '" + input + "'");
             }
             options.live = live;
             options.encode_bitrate = encode_bitrate.value_or("");
             options.encoder = encoder;
             options.frame_rate_hz = frame_rate_hz;
             options.poll_capacity = poll_capacity;
             return std::make_unique<PyOdometry>(options);
           }),
           py::arg("calibration"), py::kw_only(), py::arg("input") = "h264", py::arg("live") = false,
           py::arg("encode_bitrate") = py::none(), py::arg("encoder") = "auto", py::arg("frame_rate_hz") = 0.0,
           py::arg("poll_capacity") = 4096)
      .def("push_h264", &PyOdometry::pushH264, py::arg("t_ns"), py::arg("left"), py::arg("right"),
           R"doc(Push one frame as one H.264 access unit per camera (bytes: Annex B, SPS/PPS in band before the
first keyframe; no B-frames, one reference frame) taken at t_ns (ns, after the previous frame's).
The bytes are copied. Returns False when the live policy dropped the frame; offline, waits for room
(without the GIL). Raises voca.Error for an empty packet, a time not after the previous one (the
odometry stays usable), after finish(), and once the pipeline has stopped (a stage failed on earlier
data: the message names the stage and frame; every pose estimated before can still be polled).)doc")
      .def("push_gray", &PyOdometry::pushGray, py::arg("t_ns"), py::arg("left"), py::arg("right"),
           R"doc(Push one frame as two 8-bit gray images (NumPy uint8, shape (height, width), the calibration's
size) taken at t_ns (ns, after the previous frame's). C-contiguous arrays are read in place (other
layouts are copied first); the pipeline copies the pixels. Returns and raises as push_h264; an image
of another size than the calibration's raises voca.Error naming both sizes.)doc")
      .def("poll", &PyOdometry::poll,
           "The oldest estimated pose not yet polled (voca.Pose), or None when none is waiting. Never blocks.")
      .def("poses", &PyOdometry::poses,
           "Every pose waiting, polled at once: a float64 (N, 8) array of TUM rows [t_s, x, y, z, qx, qy, qz, qw] "
           "(N may be 0), the numbers `voca run --out` writes.")
      .def("finish", &PyOdometry::finish, py::arg("discard") = false,
           R"doc(End the input and wait (without the GIL) until the pipeline has stopped; returns the run's summary
as a dict: frames, keyframes, resets, lost, dropped, damaged, frames_lost, unpaired, threads, wall_s,
fps, end_to_end_ms {p50, p90, p99, max}, error (why a stage failed; '' otherwise), failure, warnings,
report (the summary `voca run` prints), latency_report, input, config, started, stopped. discard=True
drops the frames not yet estimated instead of processing them. Later calls return the same summary;
poses estimated before can still be polled.)doc")
      .def_property_readonly("running", &PyOdometry::running,
                             "False once the pipeline has stopped: finished, stopped, or failed (see error).")
      .def_property_readonly("error", &PyOdometry::error,
                             "Why the pipeline stopped early ('<stage> stage failed at frame N: ...'); '' otherwise.")
      .def_property_readonly("description", &PyOdometry::description,
                             "The configuration used and the decoder chosen, for logs.")
      .def("__enter__", [](py::object self) { return self; })
      .def(
          "__exit__",
          [](PyOdometry& self, const py::object& type, const py::object&, const py::object&) {
            if (type.is_none()) {
              self.finish(false);
              return false;
            }
            // The block's own exception is the one to see; a failure of the pipeline is in error.
            try {
              self.finish(true);
            } catch (const voca_rt::Error&) {
            }
            return false;
          },
          "Finishes: flushing every pushed frame, or discarding the waiting ones when the block raised.");

  static const std::string run_doc = std::string(kRunDoc) + voca_python::sharedOptionsDoc() + kRunDocEnd;
  m.def(
      "run",
      [](const std::filesystem::path& path, const OptionalPath& calib, const py::object& mode, const py::object& config,
         const std::optional<std::string>& encode, int max_frames, int first_frame, const py::object& threads,
         const OptionalPath& gt, bool realtime, double speed, double stream_wait_s, double stream_timeout_s,
         bool return_summary, const py::kwargs& shared_options) {
        voca_rt::Options options;
        options.calibration_file = pathText(calib);
        voca_python::setSharedOption(options, "mode", mode, "voca.run");
        voca_python::setSharedOption(options, "config", config, "voca.run");
        voca_python::setSharedOption(options, "threads", threads, "voca.run");
        voca_python::setSharedOptions(options, shared_options, "voca.run");
        return runPath(path, options, gt, encode, max_frames, first_frame, realtime, speed, stream_wait_s,
                       stream_timeout_s, return_summary);
      },
      py::arg("path"), py::arg("calib") = py::none(), py::arg("mode") = py::none(), py::arg("config") = py::none(),
      py::arg("encode") = py::none(), py::arg("max_frames") = 0, py::arg("first_frame") = 0, py::arg("threads") = 0,
      py::kw_only(), py::arg("gt") = py::none(), py::arg("realtime") = false, py::arg("speed") = 1.0,
      py::arg("stream_wait_s") = 30.0, py::arg("stream_timeout_s") = 3.0, py::arg("return_summary") = false,
      run_doc.c_str());

  m.def("evaluate", &evaluateFiles, py::arg("gt"), py::arg("est"),
        R"doc(Evaluate an estimated trajectory file against ground truth, as `voca eval --gt GT --est EST` (the same
numbers as evo): both files TUM, EuRoC csv or KITTI, told apart by their content. Returns a dict:
associated (estimated poses matched to ground truth by time), ate_rmse_m and ate_max_m (positions
after an SE(3) Umeyama alignment, no scale), rte_rmse_m (relative translations over 6 frames without
alignment; None when the trajectory is shorter), divergent (ATE > 10 m or RTE > 10 cm). Raises
voca.Error naming a file that cannot be read or holds no pose matching the other's times.)doc");

  py::class_<PyVideoFolder>(m, "VideoFolder", R"doc(The stereo H.264 access units of a VOCA video folder.

VideoFolder(path) opens mav0/camN/data.mp4 + data.csv (what `voca encode` and `voca record` write;
path is the dataset folder or its mav0). Iterating gives (t_ns, left, right) per frame: the sensor
time and one Annex B access unit per camera (bytes, parameter sets in band), as an encoder on a robot
hands them over, ready for Odometry.push_h264. Raises voca.Error naming what is missing.)doc")
      .def(py::init<const std::filesystem::path&>(), py::arg("path"))
      .def("__iter__", [](py::object self) { return self; })
      .def("__next__", &PyVideoFolder::next, "The next frame's (t_ns, left, right); StopIteration at the end.")
      .def("__len__", &PyVideoFolder::frames, "Frames listed in data.csv.")
      .def_property_readonly("width", &PyVideoFolder::width, "Picture width in pixels.")
      .def_property_readonly("height", &PyVideoFolder::height, "Picture height in pixels.")
      .def_property_readonly("frames", &PyVideoFolder::frames, "Frames listed in data.csv.")
      .def_property_readonly("calibration_file", &PyVideoFolder::calibrationFile,
                             "The calibration written beside the videos (calib.json), or None.");
}

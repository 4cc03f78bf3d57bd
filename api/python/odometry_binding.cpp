#include "odometry_binding.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "conversions.h"
#include "shared_options.h"
#include "voca_rt/voca_rt.h"

namespace voca_python {
namespace {

// A contiguous byte view of any object with the buffer protocol (bytes, bytearray, memoryview, a
// uint8 NumPy array), held for as long as the C++ side reads it.
class ByteView {
 public:
  ByteView(const py::handle& object, const char* name) {
    if (PyObject_GetBuffer(object.ptr(), &view_, PyBUF_C_CONTIGUOUS) != 0) {
      PyErr_Clear();
      throw py::type_error(std::string(name) + ": expected bytes (one H.264 access unit), got " + typeName(object));
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

}  // namespace

void bindOdometry(py::module_& module) {
  static const std::string odometry_doc =
      std::string(kOdometryDoc) + sharedOptionsDoc() +
      "\nRaises voca.Error for a calibration, config or option that cannot be used.";
  py::class_<PyOdometry>(module, "Odometry", odometry_doc.c_str())
      .def(py::init([](const OptionalPath& calibration, const std::string& input, bool live,
                       const std::optional<std::string>& encode_bitrate, const std::string& encoder,
                       double frame_rate_hz, std::size_t poll_capacity, const py::kwargs& shared_options) {
             voca_rt::Options options;
             options.calibration_file = pathText(calibration);
             setSharedOptions(options, shared_options, "voca.Odometry");
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
}

}  // namespace voca_python

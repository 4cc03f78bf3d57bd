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

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "conversions.h"
#include "odometry_binding.h"
#include "run_binding.h"
#include "voca_rt/voca_rt.h"

namespace voca_python {
namespace {

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

}  // namespace
}  // namespace voca_python

PYBIND11_MODULE(voca, m) {
  using namespace voca_python;

  m.doc() = kModuleDoc;
  m.attr("__version__") = VOCA_RT_VERSION;
  addErrorType(m);

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

  bindOdometry(m);
  bindRun(m);

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

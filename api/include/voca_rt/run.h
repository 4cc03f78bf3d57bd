#pragma once
// One-call runs on inputs the library opens itself: what `voca run` and `voca live` do, with the poses
// delivered to a callback as they are estimated.
//
//   voca_rt::Options options;                           // calibration found beside the dataset
//   options.trajectory_file = "traj.txt";
//   voca_rt::Summary summary = voca_rt::run({.path = "MH_01_easy"}, options);

#include <cstdint>
#include <string>

#include "voca_rt/export.h"
#include "voca_rt/odometry.h"

namespace voca_rt {

// A recorded input, as `voca run <input>` takes it.
struct Input {
  // A EuRoC/TUM-VI or KITTI folder (raw images), a VOCA video folder (mav0/camN/data.mp4), a stream URL
  // that `voca stream` sends to (udp://127.0.0.1:5000, tcp://...), or a stream it recorded to a file.
  std::string path;
  int first_frame = 0;       // track from this frame on (videos are still decoded from their start)
  int max_frames = 0;        // 0: all
  std::string ground_truth;  // TUM/EuRoC/KITTI trajectory for ATE/RTE; empty: the dataset's own, if any
  // Raw datasets: encode first the way the paper did (two-pass x264 at this bitrate, "500k") into a
  // temporary folder, removed afterwards; empty: track the raw images.
  std::string encode_bitrate;
  bool realtime = false;          // replay at the recording's timestamps (live policy); false: as fast as it goes
  double speed = 1.0;             // with realtime: playback speed
  double stream_wait_s = 30.0;    // stream URLs: how long to wait for the stream to begin
  double stream_timeout_s = 3.0;  // stream URLs: silence that ends the run
};

// Cameras, as `voca live` takes them (V4L2 devices, libcamera cameras when built with it).
struct CameraInput {
  // "LEFT,RIGHT" devices (/dev/video0,/dev/video2), "libcamera:0,libcamera:1", or one side-by-side
  // stereo device, split into halves.
  std::string devices;
  std::string size;                // "640x480" per device; empty: the device's current size
  std::string pixel_format;        // GREY, Y10, Y16, YUYV or NV12; empty: the first of these the device offers
  double fps = 0.0;                // 0: the devices' current rate
  int exposure = -1;               // manual exposure in the device's units; -1: automatic
  int gain = -1;                   // manual gain; -1: automatic
  double pair_tolerance_ms = 0.0;  // most time between a pair's timestamps; 0: just under half a frame
  int buffers = 4;                 // kernel capture buffers per device, 2-32
  std::int64_t max_frames = 0;     // 0: until stopped
};

// Runs the odometry over the input (Options::calibration_file overrides the dataset's own; a stream
// needs one), calling on_pose for each frame as it is estimated. Options::input, live, frame_rate_hz,
// encoder and poll_capacity do not apply (the input decides). Throws Error for bad input found before
// the run (a missing dataset, calibration or config; images that do not match the calibration); a
// stage failing during the run does not throw: Summary::error says why, with everything estimated
// up to then kept.
VOCA_RT_API Summary run(const Input& input, const Options& options, const PoseCallback& on_pose = {});

// The same on live cameras, with the live policy, until max_frames, a stop request or a device failure.
VOCA_RT_API Summary runCameras(const CameraInput& cameras, const Options& options, const PoseCallback& on_pose = {});

}  // namespace voca_rt

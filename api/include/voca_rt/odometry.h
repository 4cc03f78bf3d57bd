#pragma once
// The odometry object: stereo frames in, one pose per frame out, through the same staged pipeline as
// `voca run` (read -> [encode] -> [decode] -> frontend -> backend -> write on threads of their own,
// fixed memory). A program pushes either
//  - one H.264 access unit per camera (Annex B byte stream, SPS/PPS in band before the first
//    keyframe; no B-frames, one reference frame) with the frames' sensor time: the compressed path,
//    where the codec's motion vectors become the tracker's priors; or
//  - two 8-bit gray images with their sensor time: the raw path, or, with Options::encode_bitrate,
//    the on-device path (each camera encoded by the live encoder, then decoded with its vectors).
// Each estimated pose comes back through the callback, on the pipeline's output thread, and through
// poll() on any thread. One thread may push while another polls.
//
//   voca_rt::Options options;
//   options.calibration_file = "calib.json";
//   voca_rt::Odometry odometry(options, [](const voca_rt::Pose& pose) { /* must not block */ });
//   odometry.pushH264(t_ns, left.data(), left.size(), right.data(), right.size());
//   voca_rt::Summary summary = odometry.finish();

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "voca_rt/calibration.h"
#include "voca_rt/error.h"
#include "voca_rt/export.h"

namespace voca_rt {

enum class TrackingState : std::uint8_t {
  kOk,     // estimated in the sliding window
  kReset,  // tracking failed and restarted from this frame's stereo at the last good pose
  kLost,   // no estimate possible for this frame; the last good pose is repeated
};

// What an odometry's pushes deliver.
enum class InputKind : std::uint8_t {
  kH264,  // pushH264: one access unit per camera
  kGray,  // pushGray: one 8-bit image per camera
};

// Time each stage spent on the frame, and from its arrival to its pose (wall clock, milliseconds).
// Stages the run does not have (decode on the raw path, encode without encode_bitrate) are 0.
struct StageLatency {
  double encode_ms = 0.0;
  double decode_ms = 0.0;
  double frontend_ms = 0.0;
  double backend_ms = 0.0;
  double end_to_end_ms = 0.0;
};

struct Pose {
  std::int64_t t_ns = 0;             // the frame's sensor time, as pushed
  std::int64_t frame_index = 0;      // the frame's place among the frames pushed, from 0
  std::array<double, 3> position{};  // T_world_body's translation, metres
  // T_world_body's rotation as a unit quaternion x, y, z, w. The world frame is the first frame's body
  // pose; the body frame is the calibration's (the IMU for Basalt and Kalibr files).
  std::array<double, 4> orientation{0.0, 0.0, 0.0, 1.0};
  TrackingState state = TrackingState::kLost;
  bool keyframe = false;
  int landmarks = 0;  // alive in the window
  int inliers = 0;    // this frame's observations of landmarks
  StageLatency latency;

  // T_world_body as a row-major 4x4 matrix.
  VOCA_RT_API std::array<double, 16> matrix() const;
};

// The row `voca run --out` writes for the pose in the TUM format: "t tx ty tz qx qy qz qw\n", the
// time in seconds with nine decimals, numbers in their shortest exact form.
VOCA_RT_API std::string tumRow(const Pose& pose);

// Called once per frame in frame order on the pipeline's output thread. It must return quickly and
// must not block (the pipeline waits for it); copy the pose out and work elsewhere.
using PoseCallback = std::function<void(const Pose& pose)>;

// Where ROS 2 odometry goes (Options::ros2), as `voca run --ros2` and its --ros2-* options.
struct Ros2Output {
  std::string topic = "/odom";           // nav_msgs/msg/Odometry; relative names are in the root namespace
  std::string odom_frame = "odom";       // header.frame_id: the first frame's body pose
  std::string base_frame = "base_link";  // child_frame_id: the calibration's body frame
  int domain_id = -1;                    // the DDS domain, 0 to 232; -1: ROS_DOMAIN_ID (unset: 0)
};

struct Options {
  // The stereo calibration: a file (Basalt JSON, Kalibr YAML, EuRoC sensor.yaml, KITTI calib.txt), or
  // a value (used when it has cameras).
  std::string calibration_file;
  Calibration calibration;
  // A shipped config by name (euroc, tumvi, kitti) or a JSON config file; empty: euroc.
  std::string config;
  // The prior mode (none, mv, of_then_mv, mv_then_of, mv_parallel_of); empty: the config's.
  std::string mode;
  // I-frame bridging (reuse the last P-frame's motion on I-frames); empty: the config's.
  std::optional<bool> bridge_iframes;
  int max_points = 1000;  // tracker capacity per camera
  bool estimate = true;   // false: track features only (no poses; Summary::report is the tracker's)

  // How the pipeline runs, as the command line's --threads, --frontend-threads, --pin, --sched,
  // --priority, --mlock, --strict, --decoder, --skip-deblock.
  int threads = 0;                   // 0: one per stage; 1: every stage on one thread; N: stages grouped on N
  int frontend_threads = 0;          // 0: automatic; 1 or 2 (a helper thread takes about half the points)
  std::string pins;                  // stage-to-core map, "decode:0,frontend:0,backend:1"; empty: none
  std::string scheduling = "other";  // other, fifo or rr (real-time classes need CAP_SYS_NICE)
  int priority = 50;                 // for fifo and rr, 1-99
  bool lock_memory = false;          // mlockall before the first frame
  bool strict = false;               // a damaged frame stops the run instead of being skipped
  std::string decoder = "auto";      // auto, software, vaapi, v4l2m2m
  bool skip_deblock = false;         // software decoding without H.264's loop filter

  // Pushed frames.
  InputKind input = InputKind::kH264;
  // Live policy: push never waits (a frame the pipeline has no room for is dropped and counted) and a
  // stage that falls behind drops the oldest waiting frame. Off (offline): push waits for room and
  // every frame is processed in order, so the same frames always give the same poses.
  bool live = false;
  double frame_rate_hz = 0.0;  // the cameras' rate, for the on-device encoder's rate control; 0: 20 Hz
  // Gray frames: encode each camera on the device first at this bitrate ("1M", "500k"), then decode
  // with motion vectors, as `voca run --encode` does for a dataset; empty: track the raw images.
  std::string encode_bitrate;
  std::string encoder = "auto";      // auto, x264, v4l2m2m, vaapi
  std::size_t poll_capacity = 4096;  // poses kept for poll(); beyond, the oldest unpolled are dropped

  // Outputs, written as the run goes (empty: none).
  std::string trajectory_file;
  std::string trajectory_format = "tum";  // tum, euroc or kitti
  std::string statistics_file;            // JSON, written when the run ends
  std::string trace_file;                 // Chrome trace-event JSON of every frame's stages
  bool progress = false;                  // progress lines on stderr
  // Each tracked pose published into a ROS 2 graph over DDS (Cyclone DDS; ROS itself not needed) as
  // odometry and on /tf, by a thread of its own that never holds the pipeline up. Needs estimate.
  std::optional<Ros2Output> ros2;
  // Live view ("[host:]port", as `voca run --view`): a web page at http://host:port/ and the Foxglove
  // WebSocket protocol at ws://host:port with the left camera and its tracks, the path, the landmarks and
  // the latency per stage; bound before the input opens. A slow client misses messages, never slows the
  // run. Empty: none.
  std::string view_address;
  double view_image_rate_hz = 10.0;  // camera images per second at most, for the view and the recording
  // The view's channels recorded to this MCAP file as the run goes (Foxglove, Lichtblick); a write error
  // stops the recording with a warning, not the run. Empty: none.
  std::string mcap_file;

  // Polled between frames: true stops the run as Ctrl-C stops the command line (what was estimated
  // is kept). Empty: only finish() or the destructor stop it.
  std::function<bool()> stop_requested;
};

// What a run did.
struct Summary {
  std::string input;        // what was run on, one line ("video folder seq (2x 752x480 h264)")
  std::string config;       // the config's file or shipped name
  bool started = false;     // frames began to flow (false: stopped or failed before the first)
  std::int64_t frames = 0;  // frames that passed every stage (one pose each)
  std::int64_t keyframes = 0, resets = 0, lost = 0;
  std::int64_t dropped = 0;      // live policy: frames a stage skipped to keep up
  std::int64_t damaged = 0;      // frames whose data could not be decoded
  std::int64_t frames_lost = 0;  // before the pipeline: pushes it had no room for, network or driver losses
  std::int64_t unpaired = 0;     // frames of one camera without a partner (cameras, streams)
  int threads = 0;               // pipeline threads, the frontend's helper included
  double wall_s = 0.0;
  double frames_per_second = 0.0;
  // Arrival of a frame to its pose (wall clock): median, 90th and 99th percentile and maximum, ms.
  std::array<double, 4> end_to_end_ms{};
  std::optional<double> ate_rmse_m, rte_rmse_m;  // against ground truth, when the input has it
  int stop_signal = 0;                           // the signal that stopped a command-line run (0: none)
  bool stopped = false;                          // a stop request ended the run before its input did
  std::string error;    // a stage failed: "<stage> stage failed at frame N: <why>"; empty: none
  std::string failure;  // no pose was estimated (every frame lost): why; empty otherwise
  std::vector<std::string> warnings;
  std::string report;          // the summary as `voca run` prints it
  std::string latency_report;  // the latency table of `voca run --profile`
  std::string ros2_summary;    // with Options::ros2: what was published, one line
};

class VOCA_RT_API Odometry {
 public:
  // What finish() and the destructor do with frames pushed but not yet processed.
  enum class Stop {
    kFlush,    // process them all, then stop
    kDiscard,  // stop as soon as possible; frames not yet estimated are dropped
  };

  // Loads the calibration and config, builds the pipeline for pushed frames of the calibration's
  // image size (every buffer allocated here) and starts its threads. on_pose: see PoseCallback.
  // Throws Error for a calibration, config or option that cannot be used.
  explicit Odometry(const Options& options, PoseCallback on_pose = {}, Stop on_destroy = Stop::kFlush);
  // Stops as on_destroy says; never throws (what finish() would return is lost: call it first).
  ~Odometry();
  Odometry(const Odometry&) = delete;
  Odometry& operator=(const Odometry&) = delete;

  // One H.264 access unit per camera for the frame taken at t_ns (ns, strictly increasing). Copies
  // the bytes. Returns false when the live policy dropped the frame. Throws Error for bad input (an
  // empty packet, a time not after the previous frame's; the object stays usable) and once the
  // pipeline has stopped (a stage failed on earlier data, e.g. a stream with B-frames or pictures of
  // another size than the calibration's: the message says which and at which frame; every pose
  // estimated before is kept). For an odometry built with Options::input kH264.
  bool pushH264(std::int64_t t_ns, const std::uint8_t* left, std::size_t left_size, const std::uint8_t* right,
                std::size_t right_size);

  // One gray image per camera (8-bit, `stride` bytes per row, 0 for width) of the calibration's size,
  // for an odometry built with Options::input kGray. As pushH264 otherwise; an image of another size
  // throws Error naming both sizes.
  bool pushGray(std::int64_t t_ns, const std::uint8_t* left, const std::uint8_t* right, int width, int height,
                int stride = 0);

  // The oldest estimated pose not yet polled; false when none is waiting. Never blocks; allocates
  // nothing.
  bool poll(Pose& pose);

  // Ends the input and waits until the pipeline has stopped; returns what the run did. Later calls
  // return the same summary.
  Summary finish(Stop how = Stop::kFlush);

  // False once the pipeline has stopped: finished, stopped, or failed (error() says why).
  bool running() const;
  // Why the pipeline stopped early ("<stage> stage failed at frame N: ..."); empty otherwise.
  std::string error() const;
  // The configuration used, the decoder chosen ("decoder: software"), for logs.
  std::string description() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca_rt

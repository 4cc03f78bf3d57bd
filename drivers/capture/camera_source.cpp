#include "drivers/capture/camera_source.h"

#include <cmath>

#include <fmt/core.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>

#include "drivers/capture/pixel_format.h"
#include "drivers/capture/stereo_pairing.h"
#include "platform/realtime/clock.h"
#include "voca/core/error.h"

namespace voca::capture {

StereoCameraOptions stereoCameraOptions(const CameraSettings& settings) {
  StereoCameraOptions options;
  options.devices = parseDeviceList(settings.devices);
  if (!settings.size.empty()) parseFrameSize(settings.size, options.request.width, options.request.height);
  if (!settings.pixel_format.empty()) options.request.fourcc = parseGrayConvertibleFormat(settings.pixel_format);
  if (settings.fps < 0.0 || !std::isfinite(settings.fps))
    throw InputError(fmt::format("--fps: expected a positive rate, got {}", settings.fps));
  options.request.rate_hz = settings.fps;
  if (settings.exposure >= 0) options.request.controls.exposure = settings.exposure;
  if (settings.gain >= 0) options.request.controls.gain = settings.gain;
  if (settings.pair_tolerance_ms < 0.0 || !std::isfinite(settings.pair_tolerance_ms))
    throw InputError("--pair-tolerance: expected a positive number of milliseconds");
  options.pair_tolerance_ns = static_cast<std::int64_t>(std::llround(settings.pair_tolerance_ms * 1e6));
  if (settings.buffers < 2 || settings.buffers > 32)
    throw InputError(fmt::format("--buffers: expected 2 to 32, got {}", settings.buffers));
  options.request.buffers = settings.buffers;
  if (settings.frames < 0) throw InputError("--frames: expected 0 (until stopped) or a positive count");
  options.max_frames = settings.frames;
  return options;
}

namespace {
// poll() slices: an interrupt is seen within this long.
constexpr int kPollSliceMs = 50;
}  // namespace

void parseFrameSize(std::string_view text, int& width, int& height) {
  const std::size_t x = text.find('x');
  const auto number = [](std::string_view digits, int& value) {
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    return error == std::errc{} && end == digits.data() + digits.size() && value > 0;
  };
  if (x == std::string_view::npos || !number(text.substr(0, x), width) || !number(text.substr(x + 1), height)) {
    throw InputError(fmt::format("--size \"{}\": expected WIDTHxHEIGHT, e.g. 640x480", text));
  }
}

std::vector<std::string> parseDeviceList(std::string_view text) {
  std::vector<std::string> devices;
  std::size_t begin = 0;
  while (begin <= text.size()) {
    const std::size_t comma = std::min(text.find(',', begin), text.size());
    const std::string_view device = text.substr(begin, comma - begin);
    if (device.empty()) {
      throw InputError(
          fmt::format("--camera \"{}\": expected DEVICE or LEFT,RIGHT (e.g. /dev/video0,/dev/video2)", text));
    }
    devices.emplace_back(device);
    begin = comma + 1;
  }
  if (devices.size() > 2) throw InputError(fmt::format("--camera \"{}\": at most two devices (left,right)", text));
  if (devices.size() == 2 && devices[0] == devices[1]) {
    throw InputError(fmt::format("--camera \"{}\": the left and right devices are the same", text));
  }
  return devices;
}

CameraStereoSource::CameraStereoSource(const StereoCameraOptions& options, platform::V4l2Io& io)
    : options_(options), io_(io) {
  if (options_.devices.empty() || options_.devices.size() > 2) {
    throw InputError("cameras: expected one side-by-side stereo device or two devices (left, right)");
  }
  for (const std::string& device : options_.devices) {
    cameras_.push_back(std::make_unique<V4l2Camera>(io, device, options_.request));
  }
  side_by_side_ = cameras_.size() == 1;
  const CameraFormat& left = cameras_[0]->format();
  if (side_by_side_) {
    if (left.width % 2 != 0) {
      throw InputError(fmt::format("{}: a side-by-side stereo frame must have an even width, got {}",
                                   cameras_[0]->path(), left.width));
    }
    info_.width = left.width / 2;
    info_.height = left.height;
    info_.description = fmt::format("side-by-side stereo camera {}, split into 2x {}x{}", cameras_[0]->description(),
                                    info_.width, info_.height);
  } else {
    const CameraFormat& right = cameras_[1]->format();
    if (left.width != right.width || left.height != right.height) {
      throw InputError(fmt::format("{} captures {}x{} but {} captures {}x{}; the stereo cameras must match",
                                   cameras_[0]->path(), left.width, left.height, cameras_[1]->path(), right.width,
                                   right.height));
    }
    info_.width = left.width;
    info_.height = left.height;
    info_.description = fmt::format("stereo cameras {} + {}", cameras_[0]->description(), cameras_[1]->description());
  }
  info_.kind = SourceKind::kRaw;
  info_.live = true;
  info_.expected_frames = 0;
  info_.nominal_rate_hz = left.rate_hz;
  tolerance_ns_ = options_.pair_tolerance_ns > 0 ? options_.pair_tolerance_ns : defaultPairTolerance(left.rate_hz);
}

CameraStereoSource::~CameraStereoSource() = default;

SourceCounters CameraStereoSource::counters() const {
  return {.frames_lost = frames_lost_.load(), .unpaired = unpaired_.load()};
}

std::vector<std::string> CameraStereoSource::warnings() const {
  std::vector<std::string> warnings;
  for (const auto& camera : cameras_)
    warnings.insert(warnings.end(), camera->warnings().begin(), camera->warnings().end());
  return warnings;
}

// Dequeues a buffer for every camera that has none waiting, waiting up to timeout_ms for one to
// become ready. True when every camera has one.
bool CameraStereoSource::fillPending(int timeout_ms) {
  std::array<pollfd, 2> fds{};
  std::array<int, 2> camera_of{};
  nfds_t count = 0;
  for (std::size_t c = 0; c < cameras_.size(); ++c) {
    if (!has_pending_[c]) has_pending_[c] = cameras_[c]->dequeue(pending_[c]);
    if (!has_pending_[c]) {
      fds[count] = {cameras_[c]->fd(), POLLIN, 0};
      camera_of[count] = static_cast<int>(c);
      ++count;
    }
  }
  if (count == 0) return true;
  const int ready = io_.poll(fds.data(), count, timeout_ms);
  if (ready < 0) {
    if (errno == EINTR) return false;
    throw RuntimeFailure(fmt::format("poll on the cameras failed: {}", std::strerror(errno)));
  }
  for (nfds_t i = 0; i < count; ++i) {
    if (fds[i].revents == 0) continue;
    const auto c = static_cast<std::size_t>(camera_of[i]);
    has_pending_[c] = cameras_[c]->dequeue(pending_[c]);
    // An error or hang-up with nothing to dequeue: the device is gone or broken (DQBUF would have
    // thrown for ENODEV; this catches drivers that only flag poll).
    if (!has_pending_[c] && (fds[i].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
      throw RuntimeFailure(
          fmt::format("{}: the device reported an error after {} frames (poll: {}{}{})", cameras_[c]->path(),
                      cameras_[c]->framesDequeued(), (fds[i].revents & POLLERR) ? "POLLERR " : "",
                      (fds[i].revents & POLLHUP) ? "POLLHUP " : "", (fds[i].revents & POLLNVAL) ? "POLLNVAL" : ""));
    }
  }
  for (std::size_t c = 0; c < cameras_.size(); ++c) {
    if (!has_pending_[c]) return false;
  }
  return true;
}

bool CameraStereoSource::next(RawStereoFrame& frame) {
  if (interrupted_ || (options_.max_frames > 0 && delivered_ >= options_.max_frames)) return false;
  if (!started_) {
    for (auto& camera : cameras_) camera->start();
    started_ = true;
  }
  // Time since the last pair: a camera that stops delivering, or two that never agree within the
  // tolerance, is an error rather than a silent hang.
  const std::int64_t deadline =
      platform::monotonicNs() + static_cast<std::int64_t>(options_.frame_timeout_ms) * 1'000'000;
  const std::int64_t unpaired_before = unpaired_.load();
  while (!interrupted_) {
    if (platform::monotonicNs() > deadline) {
      // Frames arrived but never paired: the clocks or rates disagree; none arrived: a camera stalled.
      for (std::size_t c = 0; c < cameras_.size() && unpaired_.load() == unpaired_before; ++c) {
        if (has_pending_[c]) continue;
        throw RuntimeFailure(fmt::format("{}: no frame for {} ms after {} frames (camera stalled?)",
                                         cameras_[c]->path(), options_.frame_timeout_ms,
                                         cameras_[c]->framesDequeued()));
      }
      throw RuntimeFailure(fmt::format(
          "{} and {}: no two frames within {:.1f} ms of each other for {} ms ({} unpaired so far); the cameras' "
          "clocks or rates differ: raise the pairing tolerance or synchronise them",
          cameras_[0]->path(), cameras_[1]->path(), static_cast<double>(tolerance_ns_) * 1e-6,
          options_.frame_timeout_ms, unpaired_.load()));
    }
    if (!fillPending(kPollSliceMs)) continue;
    if (!side_by_side_) {
      const PairDecision decision = decidePair(pending_[0].t_ns, pending_[1].t_ns, tolerance_ns_);
      if (decision != PairDecision::kPair) {
        const std::size_t older = decision == PairDecision::kDropLeft ? 0 : 1;
        cameras_[older]->requeue(pending_[older]);
        has_pending_[older] = false;
        unpaired_.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
    }
    const CapturedBuffer& left = pending_[0];
    const CameraFormat& format = cameras_[0]->format();
    if (side_by_side_) {
      convertToGray(left.data, left.bytes_used, format.fourcc, format.bytes_per_line, 0, info_.width, info_.height,
                    frame.images[0]);
      convertToGray(left.data, left.bytes_used, format.fourcc, format.bytes_per_line, info_.width, info_.width,
                    info_.height, frame.images[1]);
    } else {
      for (std::size_t c = 0; c < 2; ++c) {
        const CameraFormat& f = cameras_[c]->format();
        convertToGray(pending_[c].data, pending_[c].bytes_used, f.fourcc, f.bytes_per_line, 0, info_.width,
                      info_.height, frame.images[c]);
      }
    }
    // The pair's time: the left camera's, as datasets stamp stereo pairs.
    frame.t_ns = left.t_ns;
    if (!have_first_sequence_) {
      have_first_sequence_ = true;
      first_sequence_ = left.sequence;
    }
    frame.frame_index = static_cast<std::int64_t>(left.sequence - first_sequence_);
    std::int64_t lost = 0;
    for (std::size_t c = 0; c < cameras_.size(); ++c) {
      cameras_[c]->requeue(pending_[c]);
      has_pending_[c] = false;
      lost += cameras_[c]->framesLost();
    }
    frames_lost_.store(lost, std::memory_order_relaxed);
    ++delivered_;
    return true;
  }
  return false;
}

}  // namespace voca::capture

#include "drivers/capture/v4l2_camera.h"

#include <fcntl.h>
#include <fmt/core.h>
#include <linux/videodev2.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "drivers/capture/pixel_format.h"
#include "drivers/capture/v4l2_devices.h"
#include "platform/realtime/clock.h"
#include "platform/v4l2/v4l2_nodes.h"
#include "voca/core/error.h"

namespace voca::capture {

namespace {

std::string openFailureReason(int error) {
  switch (error) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      return "no such device";
    case EACCES:
    case EPERM:
      return "permission denied (is the user in the video group?)";
    case EBUSY:
      return "busy (another program is using it)";
    default:
      return std::strerror(error);
  }
}

}  // namespace

V4l2Camera::V4l2Camera(platform::V4l2Io& io, std::string path, const CameraRequest& request)
    : io_(io), path_(std::move(path)) {
  fd_ = io_.open(path_, O_RDWR | O_NONBLOCK);
  if (fd_ < 0) throw InputError(unavailableDeviceMessage(io_, path_, openFailureReason(errno)));
  try {
    platform::V4l2NodeInfo info;
    if (!platform::queryCapabilities(io_, fd_, info)) {
      throw InputError(unavailableDeviceMessage(io_, path_, "not a V4L2 device"));
    }
    if (!isCameraNode(info.capabilities)) {
      const bool codec = (info.capabilities & (V4L2_CAP_VIDEO_M2M | V4L2_CAP_VIDEO_M2M_MPLANE)) != 0;
      throw InputError(unavailableDeviceMessage(
          io_, path_,
          fmt::format("not a camera ({} {})", info.driver,
                      codec ? "is a memory-to-memory codec" : "has no streaming video capture")));
    }
    driver_ = info.driver;
    card_ = info.card;
    negotiateFormat(request);
    setRate(request.rate_hz);
    applyControls(request.controls);

    v4l2_requestbuffers buffers{};
    buffers.count = static_cast<std::uint32_t>(std::max(request.buffers, 2));
    buffers.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffers.memory = V4L2_MEMORY_MMAP;
    if (platform::xioctl(io_, fd_, VIDIOC_REQBUFS, &buffers) != 0) fail("VIDIOC_REQBUFS");
    if (buffers.count < 2)
      throw RuntimeFailure(fmt::format("{}: the driver granted only {} buffer", path_, buffers.count));
    for (std::uint32_t i = 0; i < buffers.count; ++i) {
      v4l2_buffer buffer{};
      buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buffer.memory = V4L2_MEMORY_MMAP;
      buffer.index = i;
      if (platform::xioctl(io_, fd_, VIDIOC_QUERYBUF, &buffer) != 0) fail("VIDIOC_QUERYBUF");
      void* address = io_.mmap(buffer.length, fd_, buffer.m.offset);
      if (address == MAP_FAILED) fail("mmap");
      mappings_.push_back({address, buffer.length});
    }
  } catch (...) {
    for (const Mapping& mapping : mappings_) io_.munmap(mapping.address, mapping.length);
    io_.close(fd_);
    throw;
  }
}

V4l2Camera::~V4l2Camera() {
  stop();
  for (const Mapping& mapping : mappings_) io_.munmap(mapping.address, mapping.length);
  io_.close(fd_);
}

void V4l2Camera::fail(const std::string& call) const {
  const int error = errno;
  if (error == ENODEV) throw RuntimeFailure(fmt::format("{}: the device disappeared ({} failed: ENODEV)", path_, call));
  throw RuntimeFailure(fmt::format("{}: {} failed: {}", path_, call, std::strerror(error)));
}

void V4l2Camera::negotiateFormat(const CameraRequest& request) {
  std::vector<std::uint32_t> offered;
  v4l2_fmtdesc description{};
  description.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  for (description.index = 0; platform::xioctl(io_, fd_, VIDIOC_ENUM_FMT, &description) == 0; ++description.index) {
    offered.push_back(description.pixelformat);
  }
  std::string offered_list;
  for (const std::uint32_t f : offered) offered_list += (offered_list.empty() ? "" : ", ") + platform::fourccName(f);
  const auto offers = [&](std::uint32_t f) { return std::find(offered.begin(), offered.end(), f) != offered.end(); };

  std::uint32_t fourcc = request.fourcc;
  if (fourcc != 0) {
    if (!isGrayConvertible(fourcc)) {
      throw InputError(fmt::format("pixel format {}: not supported (expected one of {})", platform::fourccName(fourcc),
                                   grayConvertibleList()));
    }
    if (!offers(fourcc)) {
      throw InputError(
          fmt::format("{}: does not offer {} (it offers {})", path_, platform::fourccName(fourcc), offered_list));
    }
  } else {
    std::size_t count = 0;
    const std::uint32_t* preferred = grayConvertibleFormats(count);
    for (std::size_t i = 0; i < count && fourcc == 0; ++i) {
      if (offers(preferred[i])) fourcc = preferred[i];
    }
    if (fourcc == 0) {
      throw InputError(fmt::format("{}: offers {} but voca reads only {}", path_,
                                   offered_list.empty() ? "no formats" : offered_list, grayConvertibleList()));
    }
  }

  v4l2_format current{};
  current.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (platform::xioctl(io_, fd_, VIDIOC_G_FMT, &current) != 0) fail("VIDIOC_G_FMT");
  v4l2_format wanted{};
  wanted.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  wanted.fmt.pix.width = request.width > 0 ? static_cast<std::uint32_t>(request.width) : current.fmt.pix.width;
  wanted.fmt.pix.height = request.height > 0 ? static_cast<std::uint32_t>(request.height) : current.fmt.pix.height;
  wanted.fmt.pix.pixelformat = fourcc;
  wanted.fmt.pix.field = V4L2_FIELD_NONE;
  v4l2_format granted = wanted;
  if (platform::xioctl(io_, fd_, VIDIOC_S_FMT, &granted) != 0) fail("VIDIOC_S_FMT");
  // Drivers adjust what they cannot do instead of failing: check what came back.
  if (granted.fmt.pix.pixelformat != fourcc) {
    throw InputError(fmt::format("{}: asked for {} but the driver chose {}", path_, platform::fourccName(fourcc),
                                 platform::fourccName(granted.fmt.pix.pixelformat)));
  }
  if ((request.width > 0 || request.height > 0) &&
      (granted.fmt.pix.width != wanted.fmt.pix.width || granted.fmt.pix.height != wanted.fmt.pix.height)) {
    throw InputError(fmt::format("{}: does not capture {}x{} in {} (nearest: {}x{}; `voca devices` lists the sizes)",
                                 path_, wanted.fmt.pix.width, wanted.fmt.pix.height, platform::fourccName(fourcc),
                                 granted.fmt.pix.width, granted.fmt.pix.height));
  }
  format_.fourcc = fourcc;
  format_.width = static_cast<int>(granted.fmt.pix.width);
  format_.height = static_cast<int>(granted.fmt.pix.height);
  const std::size_t sample_bytes = (fourcc == V4L2_PIX_FMT_GREY || fourcc == V4L2_PIX_FMT_NV12) ? 1 : 2;
  format_.bytes_per_line =
      std::max<std::size_t>(granted.fmt.pix.bytesperline, static_cast<std::size_t>(format_.width) * sample_bytes);
  format_.image_bytes = granted.fmt.pix.sizeimage;
  if (format_.width <= 0 || format_.height <= 0) {
    throw RuntimeFailure(fmt::format("{}: the driver reports a {}x{} frame", path_, format_.width, format_.height));
  }
}

void V4l2Camera::setRate(double rate_hz) {
  v4l2_streamparm parameters{};
  parameters.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (platform::xioctl(io_, fd_, VIDIOC_G_PARM, &parameters) != 0) {
    if (rate_hz > 0.0) warnings_.push_back(fmt::format("{}: the frame rate cannot be set (no VIDIOC_G_PARM)", path_));
    return;
  }
  if (rate_hz > 0.0) {
    if ((parameters.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) == 0) {
      warnings_.push_back(
          fmt::format("{}: the driver does not let the frame rate be set; capturing at its own", path_));
    } else {
      parameters.parm.capture.timeperframe = {1000, static_cast<std::uint32_t>(std::lround(rate_hz * 1000.0))};
      if (platform::xioctl(io_, fd_, VIDIOC_S_PARM, &parameters) != 0) fail("VIDIOC_S_PARM");
    }
  }
  const v4l2_fract& interval = parameters.parm.capture.timeperframe;
  format_.rate_hz = interval.numerator > 0 ? static_cast<double>(interval.denominator) / interval.numerator : 0.0;
  if (rate_hz > 0.0 && format_.rate_hz > 0.0 && std::abs(format_.rate_hz - rate_hz) > 0.01 * rate_hz) {
    warnings_.push_back(fmt::format("{}: asked for {:g} fps, the driver chose {:g}", path_, rate_hz, format_.rate_hz));
  }
}

void V4l2Camera::setControl(std::uint32_t id, int value, const char* what) {
  v4l2_queryctrl query{};
  query.id = id;
  if (platform::xioctl(io_, fd_, VIDIOC_QUERYCTRL, &query) != 0) fail("VIDIOC_QUERYCTRL");
  if (value < query.minimum || value > query.maximum) {
    throw InputError(fmt::format("{}: {} {} is outside the device's range {} to {}", path_, what, value, query.minimum,
                                 query.maximum));
  }
  v4l2_control control{};
  control.id = id;
  control.value = value;
  if (platform::xioctl(io_, fd_, VIDIOC_S_CTRL, &control) != 0) fail(fmt::format("VIDIOC_S_CTRL ({})", what));
}

void V4l2Camera::applyControls(const CaptureControls& controls) {
  // The first of the candidates the device has and has not disabled; 0 when none.
  const auto find = [&](std::initializer_list<std::uint32_t> candidates) -> std::uint32_t {
    for (const std::uint32_t id : candidates) {
      v4l2_queryctrl query{};
      query.id = id;
      if (platform::xioctl(io_, fd_, VIDIOC_QUERYCTRL, &query) == 0 && (query.flags & V4L2_CTRL_FLAG_DISABLED) == 0)
        return id;
    }
    return 0;
  };
  if (controls.exposure) {
    // UVC cameras have the absolute exposure (100 us units), sensor drivers the plain one.
    const std::uint32_t id = find({V4L2_CID_EXPOSURE_ABSOLUTE, V4L2_CID_EXPOSURE});
    if (id == 0) throw InputError(fmt::format("{}: has no exposure control", path_));
    if (find({V4L2_CID_EXPOSURE_AUTO}) != 0) setControl(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "auto exposure");
    setControl(id, *controls.exposure, "exposure");
  }
  if (controls.gain) {
    const std::uint32_t id = find({V4L2_CID_GAIN, V4L2_CID_ANALOGUE_GAIN});
    if (id == 0) throw InputError(fmt::format("{}: has no gain control", path_));
    if (find({V4L2_CID_AUTOGAIN}) != 0) setControl(V4L2_CID_AUTOGAIN, 0, "automatic gain");
    setControl(id, *controls.gain, "gain");
  }
}

std::string V4l2Camera::description() const {
  return fmt::format("{} ({}, {}) {}x{} {}{}", path_, driver_, card_, format_.width, format_.height,
                     platform::fourccName(format_.fourcc),
                     format_.rate_hz > 0.0 ? fmt::format(" {:g} fps", format_.rate_hz) : "");
}

void V4l2Camera::start() {
  if (streaming_) return;
  for (std::size_t i = 0; i < mappings_.size(); ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = static_cast<std::uint32_t>(i);
    if (platform::xioctl(io_, fd_, VIDIOC_QBUF, &buffer) != 0) fail("VIDIOC_QBUF");
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (platform::xioctl(io_, fd_, VIDIOC_STREAMON, &type) != 0) fail("VIDIOC_STREAMON");
  streaming_ = true;
  have_sequence_ = false;
  frames_lost_ = 0;
  dequeued_ = 0;
}

void V4l2Camera::stop() {
  if (!streaming_) return;
  streaming_ = false;
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  platform::xioctl(io_, fd_, VIDIOC_STREAMOFF, &type);  // fails only for a vanished device, which stops anyway
}

bool V4l2Camera::dequeue(CapturedBuffer& out) {
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  if (platform::xioctl(io_, fd_, VIDIOC_DQBUF, &buffer) != 0) {
    if (errno == EAGAIN) return false;
    if (errno == ENODEV) {
      throw RuntimeFailure(
          fmt::format("{}: the device disappeared after {} frames (unplugged or reset)", path_, dequeued_));
    }
    fail("VIDIOC_DQBUF");
  }
  if (buffer.index >= mappings_.size()) {
    throw RuntimeFailure(fmt::format("{}: the driver returned buffer {} of {}", path_, buffer.index, mappings_.size()));
  }
  if (have_sequence_ && buffer.sequence != last_sequence_ + 1) frames_lost_ += buffer.sequence - last_sequence_ - 1;
  have_sequence_ = true;
  last_sequence_ = buffer.sequence;
  out.index = static_cast<int>(buffer.index);
  out.sequence = buffer.sequence;
  if ((buffer.flags & V4L2_BUF_FLAG_ERROR) != 0) {
    // The driver says the data is damaged: give the buffer back and count the frame as lost.
    ++frames_lost_;
    requeue(out);
    return false;
  }
  ++dequeued_;
  out.data = static_cast<const std::uint8_t*>(mappings_[buffer.index].address);
  out.bytes_used = buffer.bytesused;
  if ((buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    out.t_ns = static_cast<std::int64_t>(buffer.timestamp.tv_sec) * 1'000'000'000 +
               static_cast<std::int64_t>(buffer.timestamp.tv_usec) * 1000;
  } else {
    // Stereo pairing needs both cameras on one clock: take the dequeue time rather than an unknown one.
    monotonic_ = false;
    if (!warned_clock_) {
      warned_clock_ = true;
      warnings_.push_back(fmt::format(
          "{}: the driver's timestamps are not CLOCK_MONOTONIC; frames are stamped when dequeued instead", path_));
    }
    out.t_ns = platform::monotonicNs();
  }
  return true;
}

void V4l2Camera::requeue(const CapturedBuffer& out) {
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  buffer.index = static_cast<std::uint32_t>(out.index);
  if (platform::xioctl(io_, fd_, VIDIOC_QBUF, &buffer) != 0) fail("VIDIOC_QBUF");
}

}  // namespace voca::capture

#include "tests/fake_v4l2.h"

#include <sys/mman.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <thread>

#include "platform/realtime/clock.h"

namespace voca::test {

std::uint8_t fakePixel(int x, int y, std::uint32_t sequence) {
  // Blocks of 4x4 pixels with hashed intensities, drifting one pixel right per frame.
  const auto bx = static_cast<std::uint32_t>((x + 1024 - static_cast<int>(sequence % 1024)) / 4);
  const auto by = static_cast<std::uint32_t>(y / 4);
  std::uint32_t h = bx * 73856093u ^ by * 19349663u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return static_cast<std::uint8_t>(h & 0xff);
}

namespace {

constexpr int kMaxBuffers = 16;
constexpr std::uint32_t kOffsetStep = 1u << 20;  // mmap offsets of successive buffers (page-aligned cookies)

std::size_t sampleBytes(std::uint32_t fourcc) {
  return (fourcc == V4L2_PIX_FMT_GREY || fourcc == V4L2_PIX_FMT_NV12) ? 1 : 2;
}

void copyName(std::uint8_t* destination, std::size_t size, const std::string& text) {
  std::memset(destination, 0, size);
  std::memcpy(destination, text.data(), std::min(text.size(), size - 1));
}

}  // namespace

struct FakeV4l2::Device {
  enum class State { kUser, kQueued };
  struct Buffer {
    std::vector<std::uint8_t> memory;
    State state = State::kUser;
    bool mapped = false;
  };

  FakeCameraSpec spec;
  std::uint32_t fourcc = 0;
  int width = 0, height = 0;
  double rate_hz = 0.0;
  std::vector<Buffer> buffers;
  std::array<int, kMaxBuffers> queue{};  // queued buffer indices, oldest first
  int queued = 0;
  bool streaming = false;
  bool vanished = false;
  std::uint32_t next_sequence = 0;
  std::uint32_t last_sequence = 0;
  int delivered = 0;
  std::int64_t stream_start_ns = 0;
  std::map<std::uint32_t, int> controls;

  std::size_t bytesPerLine() const { return static_cast<std::size_t>(width) * sampleBytes(fourcc) + spec.line_padding; }
  std::size_t imageBytes() const {
    const std::size_t luma = bytesPerLine() * static_cast<std::size_t>(height);
    return fourcc == V4L2_PIX_FMT_NV12 ? luma + luma / 2 : luma;
  }
  std::int64_t periodNs() const { return static_cast<std::int64_t>(std::llround(1e9 / rate_hz)); }
  std::int64_t dueNs(std::uint32_t sequence) const { return stream_start_ns + periodNs() * sequence; }

  bool offers(std::uint32_t f) const {
    return std::find(spec.formats.begin(), spec.formats.end(), f) != spec.formats.end();
  }

  void fill(std::uint8_t* out, std::uint32_t sequence) const {
    const std::size_t pitch = bytesPerLine();
    for (int y = 0; y < height; ++y) {
      std::uint8_t* line = out + static_cast<std::size_t>(y) * pitch;
      for (int x = 0; x < width; ++x) {
        const std::uint8_t g = fakePixel(x, y, sequence);
        const auto i = static_cast<std::size_t>(x);
        switch (fourcc) {
          case V4L2_PIX_FMT_GREY:
          case V4L2_PIX_FMT_NV12:
            line[i] = g;
            break;
          case V4L2_PIX_FMT_Y10: {  // low two bits vary so a converter must shift them out
            const unsigned word = (static_cast<unsigned>(g) << 2) | ((static_cast<unsigned>(x) + sequence) & 3u);
            line[2 * i] = static_cast<std::uint8_t>(word & 0xff);
            line[2 * i + 1] = static_cast<std::uint8_t>(word >> 8);
            break;
          }
          case V4L2_PIX_FMT_Y16:
            line[2 * i] = static_cast<std::uint8_t>(x * 37 + y);  // low byte: noise to discard
            line[2 * i + 1] = g;
            break;
          case V4L2_PIX_FMT_YUYV:
            line[2 * i] = g;
            line[2 * i + 1] = static_cast<std::uint8_t>((x & 1) ? 200 : 50);  // V / U
            break;
          default:
            break;
        }
      }
      std::memset(line + static_cast<std::size_t>(width) * sampleBytes(fourcc), 0xEE, spec.line_padding);
    }
    if (fourcc == V4L2_PIX_FMT_NV12) {
      std::memset(out + pitch * static_cast<std::size_t>(height), 0x80, pitch * static_cast<std::size_t>(height) / 2);
    }
  }
};

struct FakeV4l2::Handle {
  Device* device = nullptr;
  bool owns_buffers = false;
};

FakeV4l2::FakeV4l2() = default;
FakeV4l2::~FakeV4l2() = default;

void FakeV4l2::add(const FakeCameraSpec& spec) {
  auto device = std::make_unique<Device>();
  device->spec = spec;
  device->fourcc = spec.formats.empty() ? 0 : spec.formats.front();
  device->width = spec.sizes.front().first;
  device->height = spec.sizes.front().second;
  device->rate_hz = spec.rates_hz.front();
  devices_[spec.path] = std::move(device);
}

void FakeV4l2::unplug(const std::string& path) { devices_.at(path)->vanished = true; }

std::optional<int> FakeV4l2::control(const std::string& path, std::uint32_t id) const {
  const Device& device = *devices_.at(path);
  const auto it = device.controls.find(id);
  if (it == device.controls.end()) return std::nullopt;
  return it->second;
}

int FakeV4l2::openHandles() const { return static_cast<int>(handles_.size()); }

int FakeV4l2::mappedBuffers() const {
  int mapped = 0;
  for (const auto& [path, device] : devices_) {
    for (const Device::Buffer& buffer : device->buffers) mapped += buffer.mapped ? 1 : 0;
  }
  return mapped;
}

std::uint32_t FakeV4l2::lastSequence(const std::string& path) const { return devices_.at(path)->last_sequence; }

FakeV4l2::Handle* FakeV4l2::handle(int fd) {
  const auto it = handles_.find(fd);
  return it == handles_.end() ? nullptr : it->second.get();
}

std::vector<std::string> FakeV4l2::deviceNodes() {
  // As the kernel's list: by node number (/dev/video2 before /dev/video10).
  std::vector<std::pair<int, std::string>> numbered;
  for (const auto& [path, device] : devices_) {
    if (device->vanished) continue;
    const std::size_t digits = path.find_last_not_of("0123456789") + 1;
    numbered.emplace_back(digits < path.size() ? std::stoi(path.substr(digits)) : -1, path);
  }
  std::sort(numbered.begin(), numbered.end());
  std::vector<std::string> nodes;
  for (auto& [number, path] : numbered) nodes.push_back(std::move(path));
  return nodes;
}

int FakeV4l2::open(const std::string& path, int /*flags*/) {
  const auto it = devices_.find(path);
  if (it == devices_.end() || it->second->vanished) {
    errno = ENOENT;
    return -1;
  }
  if (it->second->spec.busy) {
    errno = EBUSY;
    return -1;
  }
  const int fd = next_fd_++;
  handles_[fd] = std::make_unique<Handle>(Handle{it->second.get(), false});
  return fd;
}

int FakeV4l2::close(int fd) {
  Handle* h = handle(fd);
  if (h == nullptr) {
    errno = EBADF;
    return -1;
  }
  if (h->owns_buffers) {
    // Closing stops streaming; buffers still mapped stay (and are counted by mappedBuffers()).
    Device& d = *h->device;
    d.streaming = false;
    d.queued = 0;
    if (std::none_of(d.buffers.begin(), d.buffers.end(), [](const Device::Buffer& b) { return b.mapped; })) {
      d.buffers.clear();
    }
  }
  handles_.erase(fd);
  return 0;
}

void* FakeV4l2::mmap(std::size_t length, int fd, std::int64_t offset) {
  Handle* h = handle(fd);
  if (h == nullptr || offset % kOffsetStep != 0) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  const auto index = static_cast<std::size_t>(offset / kOffsetStep);
  if (index >= h->device->buffers.size() || length > h->device->buffers[index].memory.size()) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  h->device->buffers[index].mapped = true;
  return h->device->buffers[index].memory.data();
}

int FakeV4l2::munmap(void* address, std::size_t /*length*/) {
  for (const auto& [path, device] : devices_) {
    for (Device::Buffer& buffer : device->buffers) {
      if (buffer.memory.data() == address && buffer.mapped) {
        buffer.mapped = false;
        return 0;
      }
    }
  }
  errno = EINVAL;
  return -1;
}

int FakeV4l2::poll(pollfd* fds, nfds_t count, int timeout_ms) {
  const std::int64_t deadline = platform::monotonicNs() + static_cast<std::int64_t>(timeout_ms) * 1'000'000;
  for (;;) {
    int ready = 0;
    std::int64_t earliest_due = deadline;
    for (nfds_t i = 0; i < count; ++i) {
      fds[i].revents = 0;
      Handle* h = handle(fds[i].fd);
      if (h == nullptr) {
        fds[i].revents = POLLNVAL;
      } else if (h->device->vanished) {
        fds[i].revents = POLLERR | POLLHUP;
      } else if (h->device->streaming && h->device->queued > 0) {
        const std::int64_t due = h->device->spec.paced ? h->device->dueNs(h->device->next_sequence) : 0;
        if (due <= platform::monotonicNs()) {
          fds[i].revents = POLLIN;
        } else {
          earliest_due = std::min(earliest_due, due);
        }
      }
      ready += fds[i].revents != 0 ? 1 : 0;
    }
    const std::int64_t now = platform::monotonicNs();
    if (ready > 0 || timeout_ms == 0 || now >= deadline) return ready;
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min(earliest_due, deadline) - now));
  }
}

int FakeV4l2::ioctl(int fd, unsigned long request, void* argument) {
  Handle* h = handle(fd);
  if (h == nullptr) {
    errno = EBADF;
    return -1;
  }
  Device& d = *h->device;
  const auto fail = [](int error) {
    errno = error;
    return -1;
  };
  if (d.vanished) return fail(ENODEV);
  const FakeCameraSpec& spec = d.spec;
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* cap = static_cast<v4l2_capability*>(argument);
      *cap = {};
      copyName(cap->driver, sizeof(cap->driver), spec.driver);
      copyName(cap->card, sizeof(cap->card), spec.card);
      copyName(cap->bus_info, sizeof(cap->bus_info), spec.bus);
      cap->device_caps = spec.capabilities;
      cap->capabilities = spec.capabilities | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_ENUM_FMT: {
      auto* desc = static_cast<v4l2_fmtdesc*>(argument);
      const bool capture =
          desc->type == V4L2_BUF_TYPE_VIDEO_CAPTURE || desc->type == V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE;
      const bool output = desc->type == V4L2_BUF_TYPE_VIDEO_OUTPUT || desc->type == V4L2_BUF_TYPE_VIDEO_OUTPUT_MPLANE;
      const bool mplane =
          desc->type == V4L2_BUF_TYPE_VIDEO_CAPTURE_MPLANE || desc->type == V4L2_BUF_TYPE_VIDEO_OUTPUT_MPLANE;
      const bool m2m = (spec.capabilities & (V4L2_CAP_VIDEO_M2M | V4L2_CAP_VIDEO_M2M_MPLANE)) != 0;
      if (mplane != ((spec.capabilities & V4L2_CAP_VIDEO_M2M_MPLANE) != 0) || (output && !m2m)) return fail(EINVAL);
      std::vector<std::pair<std::uint32_t, bool>> listed;  // fourcc, compressed
      if (capture) {
        for (const std::uint32_t f : spec.formats) listed.emplace_back(f, false);
        for (const std::uint32_t f : spec.compressed_capture) listed.emplace_back(f, true);
      } else if (output) {
        for (const std::uint32_t f : spec.compressed_output) listed.emplace_back(f, true);
      }
      if (desc->index >= listed.size()) return fail(EINVAL);
      desc->pixelformat = listed[desc->index].first;
      desc->flags = listed[desc->index].second ? V4L2_FMT_FLAG_COMPRESSED : 0;
      copyName(desc->description, sizeof(desc->description), platform::fourccName(desc->pixelformat) + " (fake)");
      return 0;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
      auto* size = static_cast<v4l2_frmsizeenum*>(argument);
      if (!d.offers(size->pixel_format) || size->index >= spec.sizes.size()) return fail(EINVAL);
      size->type = V4L2_FRMSIZE_TYPE_DISCRETE;
      size->discrete = {static_cast<std::uint32_t>(spec.sizes[size->index].first),
                        static_cast<std::uint32_t>(spec.sizes[size->index].second)};
      return 0;
    }
    case VIDIOC_ENUM_FRAMEINTERVALS: {
      auto* interval = static_cast<v4l2_frmivalenum*>(argument);
      const bool size_offered = std::find(spec.sizes.begin(), spec.sizes.end(),
                                          std::pair<int, int>(static_cast<int>(interval->width),
                                                              static_cast<int>(interval->height))) != spec.sizes.end();
      if (!d.offers(interval->pixel_format) || !size_offered || interval->index >= spec.rates_hz.size()) {
        return fail(EINVAL);
      }
      interval->type = V4L2_FRMIVAL_TYPE_DISCRETE;
      interval->discrete = {1000, static_cast<std::uint32_t>(std::lround(spec.rates_hz[interval->index] * 1000))};
      return 0;
    }
    case VIDIOC_G_FMT:
    case VIDIOC_S_FMT: {
      auto* format = static_cast<v4l2_format*>(argument);
      if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_FMT) {
        if (!d.buffers.empty()) return fail(EBUSY);
        // As drivers do: an unknown format becomes the first offered, a size the nearest offered.
        d.fourcc = d.offers(format->fmt.pix.pixelformat) ? format->fmt.pix.pixelformat : spec.formats.front();
        auto nearest = spec.sizes.front();
        for (const auto& size : spec.sizes) {
          const auto distance = [&](const std::pair<int, int>& s) {
            return std::abs(s.first - static_cast<int>(format->fmt.pix.width)) +
                   std::abs(s.second - static_cast<int>(format->fmt.pix.height));
          };
          if (distance(size) < distance(nearest)) nearest = size;
        }
        d.width = nearest.first;
        d.height = nearest.second;
      }
      format->fmt.pix = {};
      format->fmt.pix.width = static_cast<std::uint32_t>(d.width);
      format->fmt.pix.height = static_cast<std::uint32_t>(d.height);
      format->fmt.pix.pixelformat = d.fourcc;
      format->fmt.pix.field = V4L2_FIELD_NONE;
      format->fmt.pix.bytesperline = static_cast<std::uint32_t>(d.bytesPerLine());
      format->fmt.pix.sizeimage = static_cast<std::uint32_t>(d.imageBytes());
      return 0;
    }
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM: {
      auto* parm = static_cast<v4l2_streamparm*>(argument);
      if (parm->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_S_PARM) {
        const v4l2_fract& t = parm->parm.capture.timeperframe;
        if (t.numerator == 0 || t.denominator == 0) return fail(EINVAL);
        const double wanted = static_cast<double>(t.denominator) / t.numerator;
        double nearest = spec.rates_hz.front();
        for (const double rate : spec.rates_hz) {
          if (std::abs(rate - wanted) < std::abs(nearest - wanted)) nearest = rate;
        }
        d.rate_hz = nearest;
      }
      parm->parm.capture = {};
      parm->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      parm->parm.capture.timeperframe = {1000, static_cast<std::uint32_t>(std::lround(d.rate_hz * 1000))};
      return 0;
    }
    case VIDIOC_QUERYCTRL: {
      auto* query = static_cast<v4l2_queryctrl*>(argument);
      const std::uint32_t id = query->id;
      *query = {};
      query->id = id;
      query->step = 1;
      if (id == V4L2_CID_EXPOSURE_ABSOLUTE && spec.has_exposure) {
        query->type = V4L2_CTRL_TYPE_INTEGER;
        query->minimum = spec.exposure_min;
        query->maximum = spec.exposure_max;
      } else if (id == V4L2_CID_EXPOSURE_AUTO && spec.has_exposure) {
        query->type = V4L2_CTRL_TYPE_MENU;
        query->minimum = 0;
        query->maximum = 3;
      } else if (id == V4L2_CID_GAIN && spec.has_gain) {
        query->type = V4L2_CTRL_TYPE_INTEGER;
        query->minimum = spec.gain_min;
        query->maximum = spec.gain_max;
      } else {
        return fail(EINVAL);
      }
      return 0;
    }
    case VIDIOC_S_CTRL: {
      auto* control = static_cast<v4l2_control*>(argument);
      v4l2_queryctrl query{};
      query.id = control->id;
      if (ioctl(fd, VIDIOC_QUERYCTRL, &query) != 0) return -1;
      if (control->value < query.minimum || control->value > query.maximum) return fail(ERANGE);
      d.controls[control->id] = control->value;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* req = static_cast<v4l2_requestbuffers*>(argument);
      if (req->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || req->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
      if (d.streaming) return fail(EBUSY);
      for (const Device::Buffer& buffer : d.buffers) {
        if (buffer.mapped) return fail(EBUSY);  // freeing mapped buffers is refused
      }
      d.buffers.clear();
      d.queued = 0;
      req->count = std::min<std::uint32_t>(req->count, kMaxBuffers);
      d.buffers.resize(req->count);
      for (Device::Buffer& buffer : d.buffers) buffer.memory.assign(d.imageBytes(), 0);
      h->owns_buffers = req->count > 0;
      return 0;
    }
    case VIDIOC_QUERYBUF:
    case VIDIOC_QBUF: {
      auto* buffer = static_cast<v4l2_buffer*>(argument);
      if (buffer->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || buffer->memory != V4L2_MEMORY_MMAP ||
          buffer->index >= d.buffers.size()) {
        return fail(EINVAL);
      }
      Device::Buffer& b = d.buffers[buffer->index];
      if (request == VIDIOC_QUERYBUF) {
        buffer->length = static_cast<std::uint32_t>(b.memory.size());
        buffer->m.offset = buffer->index * kOffsetStep;
        return 0;
      }
      if (b.state == Device::State::kQueued || !b.mapped) return fail(EINVAL);
      b.state = Device::State::kQueued;
      d.queue[static_cast<std::size_t>(d.queued++)] = static_cast<int>(buffer->index);
      return 0;
    }
    case VIDIOC_DQBUF: {
      auto* buffer = static_cast<v4l2_buffer*>(argument);
      if (!d.streaming || buffer->memory != V4L2_MEMORY_MMAP) return fail(EINVAL);
      if (d.queued == 0) return fail(EAGAIN);
      if (spec.vanish_after_frames >= 0 && d.delivered >= spec.vanish_after_frames) {
        d.vanished = true;
        return fail(ENODEV);
      }
      if (spec.paced) {
        const std::int64_t now = platform::monotonicNs();
        if (d.dueNs(d.next_sequence) > now) return fail(EAGAIN);
        // A consumer that fell behind finds the driver dropped what did not fit in its buffers.
        const auto newest = static_cast<std::uint32_t>((now - d.stream_start_ns) / d.periodNs());
        const auto backlog = static_cast<std::uint32_t>(d.queued - 1);
        if (newest > d.next_sequence + backlog) d.next_sequence = newest - backlog;
      }
      while (std::find(spec.dropped_sequences.begin(), spec.dropped_sequences.end(), d.next_sequence) !=
             spec.dropped_sequences.end()) {
        ++d.next_sequence;
      }
      const int index = d.queue[0];
      std::copy(d.queue.begin() + 1, d.queue.begin() + d.queued, d.queue.begin());
      --d.queued;
      Device::Buffer& b = d.buffers[static_cast<std::size_t>(index)];
      b.state = Device::State::kUser;
      const std::uint32_t sequence = d.next_sequence++;
      d.fill(b.memory.data(), sequence);
      const std::int64_t t_ns =
          (spec.paced ? d.dueNs(sequence) : spec.first_t_ns + d.periodNs() * sequence) + spec.offset_ns;
      buffer->index = static_cast<std::uint32_t>(index);
      buffer->bytesused = static_cast<std::uint32_t>(b.memory.size());
      buffer->sequence = sequence;
      buffer->field = V4L2_FIELD_NONE;
      buffer->flags = V4L2_BUF_FLAG_MAPPED | V4L2_BUF_FLAG_DONE |
                      (spec.monotonic ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN);
      buffer->timestamp.tv_sec = static_cast<decltype(buffer->timestamp.tv_sec)>(t_ns / 1'000'000'000);
      buffer->timestamp.tv_usec = static_cast<decltype(buffer->timestamp.tv_usec)>((t_ns % 1'000'000'000) / 1000);
      buffer->length = static_cast<std::uint32_t>(b.memory.size());
      buffer->m.offset = static_cast<std::uint32_t>(index) * kOffsetStep;
      d.last_sequence = sequence;
      ++d.delivered;
      return 0;
    }
    case VIDIOC_STREAMON:
    case VIDIOC_STREAMOFF: {
      if (*static_cast<int*>(argument) != V4L2_BUF_TYPE_VIDEO_CAPTURE) return fail(EINVAL);
      if (request == VIDIOC_STREAMON) {
        if (d.buffers.empty()) return fail(EINVAL);
        d.streaming = true;
        d.stream_start_ns = platform::monotonicNs();
        return 0;
      }
      d.streaming = false;
      d.queued = 0;
      for (Device::Buffer& buffer : d.buffers) buffer.state = Device::State::kUser;
      return 0;
    }
    default:
      return fail(ENOTTY);
  }
}

}  // namespace voca::test

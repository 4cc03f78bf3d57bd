#include "drivers/source/push_source.h"

#include <fmt/core.h>

#include <readerwriterqueue/readerwritercircularbuffer.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "voca/core/error.h"

namespace voca {

namespace {

// How often a waiting side looks at the close and interrupt flags.
constexpr std::int64_t kPollUs = 20000;

}  // namespace

struct PushSource::Impl {
  std::vector<RawStereoFrame> raw;
  std::vector<EncodedStereoPacket> encoded;
  moodycamel::BlockingReaderWriterCircularBuffer<int> free_buffers;
  moodycamel::BlockingReaderWriterCircularBuffer<int> filled;

  explicit Impl(int capacity)
      : free_buffers(static_cast<std::size_t>(capacity)), filled(static_cast<std::size_t>(capacity)) {}

  // The pipeline side's next filled buffer, -1 at the end.
  int takeFilled(const std::atomic<bool>& closed, const std::atomic<bool>& interrupted) {
    int index = -1;
    for (;;) {
      if (interrupted.load(std::memory_order_acquire)) return -1;
      if (filled.wait_dequeue_timed(index, kPollUs)) return index;
      // close() happens after the last push was enqueued: empty and closed is the end.
      if (closed.load(std::memory_order_acquire) && filled.size_approx() == 0) {
        return filled.try_dequeue(index) ? index : -1;
      }
    }
  }
};

PushSource::PushSource(const PushSourceOptions& options)
    : impl_(std::make_unique<Impl>(std::max(options.capacity, 1))), live_(options.live) {
  if (options.width <= 0 || options.height <= 0) {
    throw InputError(fmt::format("pushed frames: an image size of {}x{}", options.width, options.height));
  }
  const int capacity = std::max(options.capacity, 1);
  info_.kind = options.kind;
  info_.description = fmt::format("{} (2x {}x{} {})", options.description, options.width, options.height,
                                  options.kind == SourceKind::kEncoded ? "h264" : "gray");
  info_.width = options.width;
  info_.height = options.height;
  info_.live = options.live;
  info_.nominal_rate_hz = options.nominal_rate_hz;
  if (options.kind == SourceKind::kEncoded) {
    impl_->encoded.resize(static_cast<std::size_t>(capacity));
    const std::size_t raw_picture =
        static_cast<std::size_t>(options.width) * static_cast<std::size_t>(options.height) * 3 / 2;
    for (EncodedStereoPacket& packet : impl_->encoded) {
      for (decode::Packet& p : packet.packets) p.bytes.reserve(raw_picture);
    }
    for (std::size_t c = 0; c < 2; ++c) {
      decode::StreamInfo& stream = info_.streams[c];
      stream.codec = decode::VideoCodec::kH264;
      stream.codec_name = "h264";
      stream.width = options.width;
      stream.height = options.height;
      stream.time_base_num = 1;  // pts count frames
      stream.time_base_den = 1;
      info_.stream_names[c] = fmt::format("pushed cam{}", c);
    }
  } else {
    impl_->raw.resize(static_cast<std::size_t>(capacity));
    for (RawStereoFrame& frame : impl_->raw) {
      for (GrayImage& image : frame.images) image.resize(options.width, options.height);
    }
  }
  for (int i = 0; i < capacity; ++i) impl_->free_buffers.try_enqueue(i);
}

PushSource::~PushSource() = default;

SourceCounters PushSource::counters() const {
  SourceCounters counters;
  counters.frames_lost = lost_.load(std::memory_order_relaxed);
  return counters;
}

void PushSource::interrupt() { interrupted_.store(true, std::memory_order_release); }

void PushSource::close() { closed_.store(true, std::memory_order_release); }

void PushSource::discardWaiting() {
  // Only the pipeline's side takes from the ring: the frames still in it are left there, and the
  // interrupt ends next() before it reaches them.
  lost_.fetch_add(static_cast<std::int64_t>(impl_->filled.size_approx()), std::memory_order_relaxed);
  interrupt();
}

std::int64_t PushSource::admit(std::int64_t t_ns) {
  if (have_last_ && t_ns <= last_t_ns_) {
    throw InputError(
        fmt::format("frame time {} ns is not after the previous frame's {} ns; times must increase", t_ns, last_t_ns_));
  }
  have_last_ = true;
  last_t_ns_ = t_ns;
  return next_index_++;
}

int PushSource::acquireFree() {
  int index = -1;
  for (;;) {
    if (interrupted_.load(std::memory_order_acquire) || closed_.load(std::memory_order_acquire)) return -1;
    if (live_) return impl_->free_buffers.try_dequeue(index) ? index : -1;
    if (impl_->free_buffers.wait_dequeue_timed(index, kPollUs)) return index;
  }
}

bool PushSource::pushEncoded(std::int64_t t_ns, std::span<const std::uint8_t> left,
                             std::span<const std::uint8_t> right) {
  if (info_.kind != SourceKind::kEncoded) throw std::logic_error("PushSource: this source takes gray images");
  if (left.empty() || right.empty()) {
    throw InputError(
        fmt::format("frame time {} ns: an empty access unit for the {} camera", t_ns, left.empty() ? "left" : "right"));
  }
  const std::int64_t frame_index = admit(t_ns);
  const int index = acquireFree();
  if (index < 0) {
    lost_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  EncodedStereoPacket& packet = impl_->encoded[static_cast<std::size_t>(index)];
  packet.t_ns = t_ns;
  packet.frame_index = frame_index;
  const std::array<std::span<const std::uint8_t>, 2> units = {left, right};
  for (std::size_t c = 0; c < 2; ++c) {
    decode::Packet& p = packet.packets[c];
    p.bytes.assign(units[c].begin(), units[c].end());
    p.pts = frame_index;
    p.dts = frame_index;
    p.index = frame_index;
    p.keyframe = false;  // the decoder finds keyframes in the stream itself
  }
  impl_->filled.wait_enqueue(index);
  return true;
}

bool PushSource::pushRaw(std::int64_t t_ns, std::array<ImageView<const std::uint8_t>, 2> images) {
  if (info_.kind != SourceKind::kRaw) throw std::logic_error("PushSource: this source takes H.264 access units");
  for (int c = 0; c < 2; ++c) {
    const ImageView<const std::uint8_t>& image = images[static_cast<std::size_t>(c)];
    if (image.width != info_.width || image.height != info_.height) {
      throw InputError(fmt::format("{}: images are {}x{} but the calibration says {}x{} for camera {}",
                                   info_.description, image.width, image.height, info_.width, info_.height, c));
    }
    if (image.data == nullptr || image.stride < image.width) {
      throw InputError(
          fmt::format("frame time {} ns: camera {}'s image has no data or a row stride of {} bytes "
                      "for {} pixels",
                      t_ns, c, image.stride, image.width));
    }
  }
  const std::int64_t frame_index = admit(t_ns);
  const int index = acquireFree();
  if (index < 0) {
    lost_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  RawStereoFrame& frame = impl_->raw[static_cast<std::size_t>(index)];
  frame.t_ns = t_ns;
  frame.frame_index = frame_index;
  frame.damaged = false;
  for (std::size_t c = 0; c < 2; ++c) {
    GrayImage& out = frame.images[c];
    out.resize(info_.width, info_.height);
    for (int y = 0; y < info_.height; ++y) {
      std::memcpy(out.row(y), images[c].row(y), static_cast<std::size_t>(info_.width));
    }
  }
  impl_->filled.wait_enqueue(index);
  return true;
}

bool PushSource::next(RawStereoFrame& frame) {
  if (info_.kind != SourceKind::kRaw) return StereoSource::next(frame);
  const int index = impl_->takeFilled(closed_, interrupted_);
  if (index < 0) return false;
  RawStereoFrame& pushed = impl_->raw[static_cast<std::size_t>(index)];
  frame.t_ns = pushed.t_ns;
  frame.frame_index = pushed.frame_index;
  frame.damaged = false;
  // Buffers change places: the slot takes the pushed images, the ring the slot's, both of one size.
  for (std::size_t c = 0; c < 2; ++c) {
    if (frame.images[c].width() != info_.width || frame.images[c].height() != info_.height) {
      frame.images[c].resize(info_.width, info_.height);
    }
    std::swap(frame.images[c], pushed.images[c]);
  }
  impl_->free_buffers.try_enqueue(index);
  return true;
}

bool PushSource::next(EncodedStereoPacket& packet) {
  if (info_.kind != SourceKind::kEncoded) return StereoSource::next(packet);
  const int index = impl_->takeFilled(closed_, interrupted_);
  if (index < 0) return false;
  EncodedStereoPacket& pushed = impl_->encoded[static_cast<std::size_t>(index)];
  packet.t_ns = pushed.t_ns;
  packet.frame_index = pushed.frame_index;
  for (std::size_t c = 0; c < 2; ++c) {
    decode::Packet& out = packet.packets[c];
    const decode::Packet& in = pushed.packets[c];
    out.bytes.assign(in.bytes.begin(), in.bytes.end());  // the slot's buffer is reserved: no allocation
    out.pts = in.pts;
    out.dts = in.dts;
    out.index = in.index;
    out.keyframe = in.keyframe;
  }
  impl_->free_buffers.try_enqueue(index);
  return true;
}

}  // namespace voca

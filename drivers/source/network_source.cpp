#include "drivers/source/network_source.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <fstream>
#include <optional>
#include <string_view>
#include <utility>

#include <fmt/core.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
}

#include "drivers/ffmpeg/av_objects.h"
#include "drivers/network/frame_stamp.h"
#include "drivers/network/open_error.h"
#include "drivers/network/stream_url.h"
#include "voca/core/error.h"

namespace voca {

namespace {

using ffmpeg::avErrorText;

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Access units waiting for their partner from the other camera. A few frames of skew between the
// cameras is normal (one socket, capture order); more means the partner was lost.
constexpr std::size_t kPendingDepth = 8;

struct Pending {
  decode::Packet packet;
  network::FrameStamp stamp;
  bool idr = false;
};

// A fixed ring of pending access units (buffers reused: no allocation once warm).
class PendingRing {
 public:
  PendingRing() : slots_(kPendingDepth) {}
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == slots_.size(); }
  Pending& front() { return slots_[head_]; }
  Pending& pushSlot() { return slots_[(head_ + size_++) % slots_.size()]; }
  void pop() {
    head_ = (head_ + 1) % slots_.size();
    --size_;
  }

 private:
  std::vector<Pending> slots_;
  std::size_t head_ = 0, size_ = 0;
};

}  // namespace

bool isStreamUrl(const std::string& input) {
  const auto scheme_end = input.find("://");
  if (scheme_end == std::string::npos || scheme_end == 0) return false;
  return std::all_of(input.begin(), input.begin() + static_cast<std::ptrdiff_t>(scheme_end),
                     [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+'; });
}

bool isRecordedStreamUrl(const std::string& url) { return url.rfind("file://", 0) == 0; }

std::filesystem::path recordedStreamFile(const std::string& url) {
  // The file protocol opens what follows "file:" ("///abs/path" is "/abs/path").
  return std::filesystem::path(url.substr(std::string_view("file:").size())).lexically_normal();
}

std::optional<std::string> recordedStreamUrl(const std::filesystem::path& path) {
  constexpr std::size_t kTsPacket = 188;
  constexpr char kSync = 0x47;
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return std::nullopt;
  std::ifstream file(path, std::ios::binary);
  std::array<char, 2 * kTsPacket + 1> head{};
  file.read(head.data(), static_cast<std::streamsize>(head.size()));
  if (file.gcount() != static_cast<std::streamsize>(head.size())) return std::nullopt;
  if (head[0] != kSync || head[kTsPacket] != kSync || head[2 * kTsPacket] != kSync) return std::nullopt;
  // libavformat's file protocol takes the path after "file:"; an absolute one keeps "file://" a URL.
  return "file://" + std::filesystem::absolute(path).string();
}

struct NetworkStereoSource::Impl {
  std::string url;
  NetworkSourceOptions options;
  AVFormatContext* format = nullptr;
  AVPacket* packet = nullptr;
  std::array<int, 2> stream_of_camera{-1, -1};
  std::array<PendingRing, 2> pending;
  std::atomic<std::int64_t> deadline_ns{0};
  std::atomic<bool>* interrupted = nullptr;
  std::int64_t last_index = -1;  // the sender's frame index of the last pair handed on
  std::int64_t max_index = -1;   // the highest frame index that arrived from either camera
  std::int64_t pairs_out = 0;
  std::int64_t tracked_out = 0;  // pairs out from options.first_frame on

  static int interruptCallback(void* opaque) {
    const auto* self = static_cast<const Impl*>(opaque);
    if (self->options.stop_requested && self->options.stop_requested()) self->interrupted->store(true);
    return (self->interrupted->load() || nowNs() > self->deadline_ns.load()) ? 1 : 0;
  }
  void armDeadline(double seconds) { deadline_ns = nowNs() + static_cast<std::int64_t>(seconds * 1e9); }

  // Strict, once the first pair went out (joining a stream before its first keyframe loses nothing):
  // the loss `what` ends the stream with an error instead of being counted.
  template <typename... Args>
  void failIfStrict(fmt::format_string<Args...> what, Args&&... args) const {
    if (!options.strict || last_index < 0) return;
    throw InputError(
        fmt::format("{}: {} (--strict stops at the first loss)", url, fmt::format(what, std::forward<Args>(args)...)));
  }

  ~Impl() {
    if (format != nullptr) avformat_close_input(&format);
    av_packet_free(&packet);
  }
};

NetworkStereoSource::NetworkStereoSource(const std::string& url, const NetworkSourceOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.url = url;
  s.options = options;
  const bool recording = isRecordedStreamUrl(url);
  s.interrupted = &interrupted_;
  if (!isStreamUrl(url)) throw InputError(fmt::format("'{}' is not a stream URL (e.g. udp://127.0.0.1:5000)", url));
  network::requireStreamPort(url);
  if (options.first_frame < 0) throw InputError("the first frame to track must not be negative");
  if (!(options.timeout_s > 0.0) || !(options.start_timeout_s > 0.0)) {
    throw InputError("network timeouts must be positive");
  }
  avformat_network_init();
  s.packet = av_packet_alloc();
  s.format = avformat_alloc_context();
  if (s.packet == nullptr || s.format == nullptr) throw RuntimeFailure("out of memory opening a network stream");
  s.format->interrupt_callback = AVIOInterruptCB{&Impl::interruptCallback, &s};
  // Hand on each access unit as the demuxer completes it: the sender writes one per PES packet,
  // and a parser would hold each one back until the next began (one frame of latency).
  s.format->flags |= AVFMT_FLAG_NOPARSE;
  AVDictionary* dict = nullptr;
  // UDP: a large socket buffer and libavformat's receive thread, so bursts (keyframes of both
  // cameras) are not dropped by the kernel while the demuxer is busy; loss of the buffer's
  // overflow is reported as a loss, not a fatal error.
  if (url.rfind("udp://", 0) == 0) {
    av_dict_set(&dict, "buffer_size", "4194304", 0);
    av_dict_set(&dict, "fifo_size", "100000", 0);
    av_dict_set(&dict, "overrun_nonfatal", "1", 0);
  }
  // Learn the two streams' sizes from the first keyframes without waiting for a frame-rate estimate.
  av_dict_set(&dict, "probesize", "2000000", 0);
  av_dict_set(&dict, "analyzeduration", "5000000", 0);
  av_dict_set(&dict, "fpsprobesize", "0", 0);
  s.armDeadline(options.start_timeout_s);
  const AVInputFormat* mpegts = av_find_input_format("mpegts");
  network::OpenErrorCapture open_error;
  int r = avformat_open_input(&s.format, url.c_str(), mpegts, &dict);
  av_dict_free(&dict);
  if (r < 0) {
    s.format = nullptr;  // freed by avformat_open_input on failure
    throw InputError(fmt::format("cannot open {}: {}", url, open_error.reason(r)));
  }
  r = avformat_find_stream_info(s.format, nullptr);
  if (interrupted_) throw InputError(fmt::format("{}: interrupted while waiting for the stream", url));
  if (recording && (r < 0 || s.format->nb_streams == 0)) {
    throw InputError(
        fmt::format("{}: not a VOCA stereo recording (two H.264 cameras in one MPEG-TS, as `voca stream "
                    "<dataset> out.ts` writes)",
                    url));
  }
  if (r < 0 || nowNs() > s.deadline_ns) {
    throw InputError(fmt::format("{}: no VOCA stereo stream arrived within {} s (is `voca stream` sending to it?)", url,
                                 options.start_timeout_s));
  }
  for (unsigned i = 0; i < s.format->nb_streams; ++i) {
    const AVCodecParameters* par = s.format->streams[i]->codecpar;
    if (par->codec_type != AVMEDIA_TYPE_VIDEO) continue;
    for (int c = 0; c < 2; ++c) {
      if (s.stream_of_camera[static_cast<std::size_t>(c)] < 0) {
        s.stream_of_camera[static_cast<std::size_t>(c)] = static_cast<int>(i);
        break;
      }
    }
  }
  if (s.stream_of_camera[1] < 0) {
    throw InputError(fmt::format("{}: expected two video streams (left and right camera), found {}", url,
                                 s.stream_of_camera[0] < 0 ? 0 : 1));
  }
  for (std::size_t c = 0; c < 2; ++c) {
    const AVStream* stream = s.format->streams[s.stream_of_camera[c]];
    const AVCodecParameters* par = stream->codecpar;
    if (par->codec_id != AV_CODEC_ID_H264) {
      throw InputError(fmt::format("{}: camera {} is {}, expected H.264", url, c, avcodec_get_name(par->codec_id)));
    }
    if (par->width <= 0 || par->height <= 0) {
      throw InputError(fmt::format("{}: camera {}'s picture size is unknown (no keyframe received yet)", url, c));
    }
    decode::StreamInfo& info = info_.streams[c];
    info.codec = decode::VideoCodec::kH264;
    info.codec_name = "h264";
    info.width = par->width;
    info.height = par->height;
    info.time_base_num = stream->time_base.num;
    info.time_base_den = stream->time_base.den;
    info.frame_rate_num = stream->avg_frame_rate.num;
    info.frame_rate_den = stream->avg_frame_rate.den > 0 ? stream->avg_frame_rate.den : 1;
    info_.stream_names[c] = fmt::format("{} cam{}", url, c);
  }
  if (info_.streams[0].width != info_.streams[1].width || info_.streams[0].height != info_.streams[1].height) {
    throw InputError(fmt::format("{}: the cameras differ in size ({}x{} and {}x{})", url, info_.streams[0].width,
                                 info_.streams[0].height, info_.streams[1].width, info_.streams[1].height));
  }
  info_.kind = SourceKind::kEncoded;
  info_.live = !recording;
  info_.first_tracked_frame = options.first_frame;
  info_.width = info_.streams[0].width;
  info_.height = info_.streams[0].height;
  info_.description = fmt::format("{} {} (2x {}x{} h264, MPEG-TS)", recording ? "recorded stream" : "network stream",
                                  url, info_.width, info_.height);
}

NetworkStereoSource::~NetworkStereoSource() = default;

SourceCounters NetworkStereoSource::counters() const {
  SourceCounters c;
  c.frames_lost = frames_lost_.load();
  c.unpaired = unpaired_.load();
  return c;
}

bool NetworkStereoSource::next(EncodedStereoPacket& out) {
  Impl& s = *impl_;
  while (true) {
    if (interrupted_) {
      end_reason_ = "interrupted";
      return false;
    }
    if (s.options.max_frames > 0 && s.tracked_out >= s.options.max_frames) {
      end_reason_ = fmt::format("{} frames received (--frames)", s.options.max_frames);
      return false;
    }
    // Pair the oldest waiting frames: equal stamps go out together, an older one has lost its partner.
    while (!s.pending[0].empty() && !s.pending[1].empty()) {
      Pending& left = s.pending[0].front();
      Pending& right = s.pending[1].front();
      if (left.stamp.frame_index == right.stamp.frame_index && left.stamp.t_ns == right.stamp.t_ns) {
        const std::int64_t index = left.stamp.frame_index;
        // After a gap the P-frames reference pictures that never arrived: libavcodec's H.264
        // decoder substitutes an older picture and returns them unflagged (wrong pixels and motion
        // vectors for one camera of a stereo pair) or withholds them until the next keyframe. For
        // accuracy the decoders restart cleanly at the next keyframe of both cameras instead (the
        // decode stage copes with withheld pictures either way). The pairs skipped count as lost.
        const bool continuous = s.last_index >= 0 && index == s.last_index + 1;
        if (!continuous) s.failIfStrict("frames {} to {} were lost", s.last_index + 1, index - 1);
        if (!continuous && !(left.idr && right.idr)) {
          s.pending[0].pop();
          s.pending[1].pop();
          continue;
        }
        if (s.last_index >= 0 && index > s.last_index + 1) frames_lost_ += index - s.last_index - 1;
        s.last_index = index;
        out.t_ns = left.stamp.t_ns;
        out.frame_index = index;
        for (std::size_t c = 0; c < 2; ++c) {
          Pending& p = s.pending[c].front();
          std::swap(out.packets[c].bytes, p.packet.bytes);
          out.packets[c].pts = p.packet.pts;
          out.packets[c].dts = p.packet.dts;
          out.packets[c].keyframe = p.packet.keyframe;
          out.packets[c].index = s.pairs_out;
          s.pending[c].pop();
        }
        ++s.pairs_out;
        if (index >= s.options.first_frame) ++s.tracked_out;
        return true;
      }
      const std::size_t older = left.stamp.frame_index < right.stamp.frame_index ? 0 : 1;
      s.failIfStrict("frame {} of camera {} has no partner from the other camera",
                     s.pending[older].front().stamp.frame_index, older);
      s.pending[older].pop();
      ++unpaired_;
    }

    s.armDeadline(s.options.timeout_s);
    av_packet_unref(s.packet);
    const int r = av_read_frame(s.format, s.packet);
    if (r < 0) {
      // Frames that arrived after the last pair handed on (waiting for a keyframe or a partner)
      // are lost too.
      if (s.last_index >= 0 && s.max_index > s.last_index) {
        if (!interrupted_ && r != AVERROR_EXIT) {
          s.failIfStrict("frames {} to {} arrived without their partners before the end", s.last_index + 1,
                         s.max_index);
        }
        frames_lost_ += s.max_index - s.last_index;
      }
      s.max_index = s.last_index;
      if (interrupted_) {
        end_reason_ = "interrupted";
      } else if (r == AVERROR_EXIT) {
        end_reason_ = fmt::format("no data for {} s", s.options.timeout_s);
      } else if (r == AVERROR_EOF) {
        end_reason_ = "end of stream";
      } else {
        end_reason_ = fmt::format("receiving failed: {}", avErrorText(r));
      }
      return false;
    }
    std::size_t camera = 2;
    for (std::size_t c = 0; c < 2; ++c) {
      if (s.packet->stream_index == s.stream_of_camera[c]) camera = c;
    }
    if (camera == 2) continue;  // another program's stream
    const std::span<const std::uint8_t> bytes(s.packet->data, static_cast<std::size_t>(s.packet->size));
    const std::optional<network::FrameStamp> stamp = network::readStamp(bytes);
    // Damaged (TS packets lost inside it) or unstamped: unusable; the gap it leaves is counted when
    // the next pair goes out. Stale (older than what was handed on): late or duplicated.
    const bool damaged = (s.packet->flags & AV_PKT_FLAG_CORRUPT) != 0 || !stamp;
    if (damaged) {
      s.failIfStrict("an access unit of camera {} after frame {} arrived {}", camera, s.last_index,
                     stamp ? "damaged (TS packets missing)" : "unstamped");
    }
    if (damaged || stamp->frame_index <= s.last_index) continue;
    s.max_index = std::max(s.max_index, stamp->frame_index);
    PendingRing& ring = s.pending[camera];
    if (ring.full()) {  // the other camera has been silent for kPendingDepth frames
      s.failIfStrict("camera {} sent nothing for {} frames after frame {}", 1 - camera, kPendingDepth, s.last_index);
      ring.pop();
      ++unpaired_;
    }
    Pending& slot = ring.pushSlot();
    slot.packet.bytes.assign(bytes.begin(), bytes.end());
    slot.packet.pts = s.packet->pts == AV_NOPTS_VALUE ? decode::kNoPts : s.packet->pts;
    slot.packet.dts = s.packet->dts == AV_NOPTS_VALUE ? decode::kNoPts : s.packet->dts;
    slot.packet.keyframe = (s.packet->flags & AV_PKT_FLAG_KEY) != 0 || network::isIdrAccessUnit(bytes);
    slot.stamp = *stamp;
    slot.idr = network::isIdrAccessUnit(bytes);
  }
}

}  // namespace voca

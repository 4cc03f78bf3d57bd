#include "drivers/decode/video_reader.h"

#include <optional>

#include "voca/core/error.h"

extern "C" {
#include <libavutil/mathematics.h>
}

namespace voca::decode {

struct VideoReader::Impl {
  std::filesystem::path path;
  Demuxer demuxer;
  std::vector<std::int64_t> t_ns;
  VideoDecoder decoder;
  Packet packet;
  bool flushed = false;
  std::int64_t frames = 0;
  std::int64_t first_pts = kNoPts;

  Impl(const std::filesystem::path& video, std::vector<std::int64_t> timestamps, const DecoderOptions& options,
       const DecoderProbe* probe)
      : path(video),
        demuxer(video),
        t_ns(std::move(timestamps)),
        decoder(demuxer.stream(), options, probe, video.string()) {}

  std::string frameCountText() const {
    return t_ns.empty() ? std::to_string(demuxer.stream().num_frames) + " in the container index"
                        : std::to_string(t_ns.size()) + " timestamps (data.csv rows)";
  }
  void checkFrame(DecodedFrame& frame);
  void checkEnd() const;
};

void VideoReader::Impl::checkFrame(DecodedFrame& frame) {
  const StreamInfo& info = demuxer.stream();
  if (frame.pts != kNoPts && info.constant_frame_rate && info.frame_rate_num > 0) {
    if (first_pts == kNoPts) first_pts = frame.pts;
    // Frame index implied by the pts at a constant rate: a jump means the decoder dropped a frame,
    // which would shift every later timestamp.
    const std::int64_t implied = av_rescale_q(frame.pts - first_pts, AVRational{info.time_base_num, info.time_base_den},
                                              AVRational{info.frame_rate_den, info.frame_rate_num});
    if (implied != frames) {
      throw InputError(path.string() + ": frame " + std::to_string(frames) + " has the pts of frame " +
                       std::to_string(implied) + ": a frame was lost in decoding (corrupt stream?)");
    }
  }
  if (!t_ns.empty()) {
    if (static_cast<std::size_t>(frames) >= t_ns.size()) {
      throw InputError(path.string() + ": has more frames than the " + std::to_string(t_ns.size()) +
                       " timestamps given (data.csv rows; frame " + std::to_string(frames) +
                       " has none); frames must follow data.csv rows one to one");
    }
    frame.t_ns = t_ns[static_cast<std::size_t>(frames)];
  }
  frame.frame_index = frames;
  ++frames;
}

void VideoReader::Impl::checkEnd() const {
  const std::int64_t expected = t_ns.empty() ? demuxer.stream().num_frames : static_cast<std::int64_t>(t_ns.size());
  if (expected > 0 && frames < expected) {
    throw InputError(path.string() + ": video ended after " + std::to_string(frames) + " frames but expected " +
                     frameCountText() + " (truncated or damaged video?)");
  }
}

VideoReader::VideoReader(const std::filesystem::path& video, std::vector<std::int64_t> t_ns,
                         const DecoderOptions& options, const DecoderProbe* probe)
    : impl_(std::make_unique<Impl>(video, std::move(t_ns), options, probe)) {
  const StreamInfo& info = impl_->demuxer.stream();
  if (!impl_->t_ns.empty() && info.num_frames > 0 && static_cast<std::size_t>(info.num_frames) != impl_->t_ns.size()) {
    throw InputError(
        video.string() + ": has " + std::to_string(info.num_frames) + " frames but " +
        std::to_string(impl_->t_ns.size()) +
        " timestamps were given (the dataset's data.csv rows); frames must follow data.csv rows one to one");
  }
}

VideoReader::~VideoReader() = default;

bool VideoReader::next(DecodedFrame& frame) {
  Impl& d = *impl_;
  for (;;) {
    if (d.decoder.receive(frame)) {
      d.checkFrame(frame);
      return true;
    }
    if (d.flushed) {
      d.checkEnd();
      return false;
    }
    if (d.demuxer.read(d.packet)) {
      d.decoder.send(d.packet);
    } else {
      d.decoder.sendEnd();
      d.flushed = true;
    }
  }
}

const StreamInfo& VideoReader::stream() const { return impl_->demuxer.stream(); }
const std::filesystem::path& VideoReader::path() const { return impl_->path; }
const std::string& VideoReader::decoderDescription() const { return impl_->decoder.description(); }
std::int64_t VideoReader::expectedFrames() const {
  return impl_->t_ns.empty() ? impl_->demuxer.stream().num_frames : static_cast<std::int64_t>(impl_->t_ns.size());
}

std::vector<std::int64_t> datasetTimestamps(const Dataset& dataset) {
  std::vector<std::int64_t> t_ns;
  t_ns.reserve(dataset.frames.size());
  for (const StereoFrameRef& frame : dataset.frames) t_ns.push_back(frame.t_ns);
  return t_ns;
}

namespace {

std::string warningsText(const Dataset& dataset) {
  std::string text;
  for (const std::string& warning : dataset.warnings) text += "; " + warning;
  return text;
}

}  // namespace

StereoVideoReader::StereoVideoReader(const Dataset& dataset, const DecoderOptions& options, const DecoderProbe* probe)
    : StereoVideoReader(
          dataset.layout == DatasetLayout::kVocaVideo
              ? dataset.video_left
              : throw InputError(dataset.root.string() + ": not a video dataset (expected mav0/cam0/data.mp4)"),
          dataset.video_right, datasetTimestamps(dataset), options, probe, warningsText(dataset)) {}

StereoVideoReader::StereoVideoReader(const std::filesystem::path& left, const std::filesystem::path& right,
                                     const std::vector<std::int64_t>& t_ns, const DecoderOptions& options,
                                     const DecoderProbe* probe, const std::string& context)
    : num_frames_(t_ns.size()) {
  try {
    left_ = std::make_unique<VideoReader>(left, t_ns, options, probe);
    DecoderOptions quiet = options;
    quiet.log_choice = false;  // one line for the pair
    right_ = std::make_unique<VideoReader>(right, t_ns, quiet, probe);
  } catch (const InputError& e) {
    throw InputError(e.what() + context);
  }
  const std::int64_t left_count = left_->stream().num_frames, right_count = right_->stream().num_frames;
  if (left_count > 0 && right_count > 0 && left_count != right_count) {
    throw InputError(left.string() + " has " + std::to_string(left_count) + " frames but " + right.string() + " has " +
                     std::to_string(right_count) + "; the cameras must have the same number of frames" + context);
  }
}

bool StereoVideoReader::next(DecodedFrame& left, DecodedFrame& right) {
  const bool have_left = left_->next(left);
  const bool have_right = right_->next(right);
  if (have_left != have_right) {
    const VideoReader& shorter = have_left ? *right_ : *left_;
    throw InputError(shorter.path().string() + ": ended at frame " +
                     std::to_string(have_left ? left.frame_index : right.frame_index) +
                     " while the other camera continues; the cameras must have the same number of frames");
  }
  return have_left;
}

}  // namespace voca::decode

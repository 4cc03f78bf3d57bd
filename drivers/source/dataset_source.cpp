#include "drivers/source/dataset_source.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "formats/image/png_io.h"
#include "voca/core/error.h"

namespace voca {

namespace {

// One past the last frame to deliver; InputError when the first frame is past the dataset's end.
std::size_t frameEnd(const Dataset& dataset, const ReplayOptions& options) {
  const std::size_t available = dataset.frames.size();
  if (options.first_frame < 0) throw InputError(fmt::format("first frame {} is negative", options.first_frame));
  const auto first = static_cast<std::size_t>(options.first_frame);
  if (available > 0 && first >= available) {
    throw InputError(fmt::format("{}: starting at frame {} leaves nothing to track: the dataset has {} frames",
                                 dataset.root.string(), first, available));
  }
  return options.max_frames > 0 ? std::min<std::size_t>(available, first + static_cast<std::size_t>(options.max_frames))
                                : available;
}

// Frames per second from the median interval of the dataset's timestamps; 0 for fewer than two.
double medianRate(const Dataset& dataset) {
  if (dataset.frames.size() < 2) return 0.0;
  std::vector<std::int64_t> intervals;
  intervals.reserve(dataset.frames.size() - 1);
  for (std::size_t i = 1; i < dataset.frames.size(); ++i) {
    intervals.push_back(dataset.frames[i].t_ns - dataset.frames[i - 1].t_ns);
  }
  std::nth_element(intervals.begin(), intervals.begin() + static_cast<std::ptrdiff_t>(intervals.size() / 2),
                   intervals.end());
  const std::int64_t median = intervals[intervals.size() / 2];
  return median > 0 ? 1e9 / static_cast<double>(median) : 0.0;
}

std::string startNote(std::size_t first) { return first > 0 ? fmt::format(" from frame {}", first) : std::string(); }

// A sequence with many unreadable images would otherwise bury the run's summary in warnings.
constexpr std::size_t kListedDamaged = 10;

std::string damagedFrameError(std::size_t index, const InputError& error) {
  return fmt::format("frame {} is damaged: {}", index, error.what());
}

}  // namespace

ImageDatasetSource::ImageDatasetSource(Dataset dataset, const ReplayOptions& options)
    : dataset_(std::move(dataset)), strict_(options.strict) {
  if (dataset_.layout == DatasetLayout::kVocaVideo) {
    throw InputError(dataset_.root.string() + ": a video folder, not an image dataset");
  }
  count_ = frameEnd(dataset_, options);
  if (count_ == 0) throw InputError(dataset_.root.string() + ": no stereo frames");
  index_ = static_cast<std::size_t>(options.first_frame);
  GrayImage left, right;
  // Non-strict replay takes the size from the first readable pair; next() reports the ones before it.
  for (std::size_t probe = index_;; ++probe) {
    try {
      readPngGray(dataset_.frames[probe].left, left);
      readPngGray(dataset_.frames[probe].right, right);
      break;
    } catch (const InputError& e) {
      if (strict_) throw InputError(damagedFrameError(probe, e));
      if (probe + 1 == count_) {
        throw InputError(fmt::format("{}: no frame of the {} to replay has both images readable; the last: {}",
                                     dataset_.root.string(), count_ - index_, e.what()));
      }
    }
  }
  if (left.width() != right.width() || left.height() != right.height()) {
    throw InputError(fmt::format("{}: left images are {}x{} but right images {}x{}", dataset_.root.string(),
                                 left.width(), left.height(), right.width(), right.height()));
  }
  info_.kind = SourceKind::kRaw;
  info_.width = left.width();
  info_.height = left.height();
  info_.expected_frames = static_cast<std::int64_t>(count_ - index_);
  info_.nominal_rate_hz = medianRate(dataset_);
  info_.description = fmt::format("raw images {} ({} frames{}, {}x{})", dataset_.root.string(), count_ - index_,
                                  startNote(index_), info_.width, info_.height);
}

bool ImageDatasetSource::next(RawStereoFrame& frame) {
  if (interrupted_ || index_ >= count_) return false;
  const StereoFrameRef& ref = dataset_.frames[index_];
  frame.t_ns = ref.t_ns;
  frame.frame_index = static_cast<std::int64_t>(index_);
  frame.damaged = false;
  try {
    readPngGray(ref.left, frame.images[0]);
    readPngGray(ref.right, frame.images[1]);
  } catch (const InputError& e) {
    // Like a video frame that cannot be decoded: skipped and counted unless the replay is strict.
    if (strict_) throw InputError(damagedFrameError(index_, e));
    if (damaged_.size() < kListedDamaged) {
      damaged_.push_back(fmt::format("frame {} skipped as damaged: {}", index_, e.what()));
    } else {
      ++unlisted_damaged_;
    }
    frame.damaged = true;
    ++index_;
    return true;
  }
  for (const GrayImage& image : frame.images) {
    if (image.width() != info_.width || image.height() != info_.height) {
      throw InputError(fmt::format("{}: frame {} is {}x{}, the first frame was {}x{}", ref.left.string(), index_,
                                   image.width(), image.height(), info_.width, info_.height));
    }
  }
  ++index_;
  return true;
}

std::vector<std::string> ImageDatasetSource::warnings() const {
  std::vector<std::string> warnings = damaged_;
  if (unlisted_damaged_ > 0) {
    warnings.push_back(fmt::format("{} more frames with unreadable images were skipped as damaged", unlisted_damaged_));
  }
  return warnings;
}

VideoFolderSource::VideoFolderSource(Dataset dataset, const ReplayOptions& options)
    : dataset_(std::move(dataset)), options_(options) {
  if (dataset_.layout != DatasetLayout::kVocaVideo) {
    throw InputError(dataset_.root.string() + ": not a video folder (expected mav0/camN/data.mp4)");
  }
  std::string context;
  for (const std::string& warning : dataset_.warnings) context += "; " + warning;
  const std::array<std::filesystem::path, 2> videos = {dataset_.video_left, dataset_.video_right};
  for (std::size_t c = 0; c < 2; ++c) {
    demuxers_[c] = std::make_unique<decode::Demuxer>(videos[c]);
    const decode::StreamInfo& stream = demuxers_[c]->stream();
    if (stream.num_frames > 0 && static_cast<std::size_t>(stream.num_frames) != dataset_.frames.size()) {
      throw InputError(fmt::format(
          "{}: has {} frames but data.csv lists {} timestamps; frames must follow data.csv rows one to one{}",
          videos[c].string(), stream.num_frames, dataset_.frames.size(), context));
    }
    info_.streams[c] = stream;
    info_.stream_names[c] = videos[c].string();
  }
  const decode::StreamInfo& left = info_.streams[0];
  const decode::StreamInfo& right = info_.streams[1];
  if (left.width != right.width || left.height != right.height) {
    throw InputError(fmt::format("{}: cam0 video is {}x{} but cam1 video {}x{}", dataset_.root.string(), left.width,
                                 left.height, right.width, right.height));
  }
  count_ = frameEnd(dataset_, options);
  if (count_ == 0) throw InputError(dataset_.root.string() + ": no stereo frames");
  // Decoding starts at the first frame whatever the start: later frames reference earlier ones.
  const auto first = static_cast<std::size_t>(options.first_frame);
  info_.kind = SourceKind::kEncoded;
  info_.width = left.width;
  info_.height = left.height;
  info_.expected_frames = static_cast<std::int64_t>(count_ - first);
  info_.first_tracked_frame = static_cast<std::int64_t>(first);
  info_.nominal_rate_hz = medianRate(dataset_);
  info_.description = fmt::format("video {} ({} frames{}, 2x {}x{} {})", dataset_.root.string(), count_ - first,
                                  startNote(first), left.width, left.height, left.codec_name);
}

VideoFolderSource::~VideoFolderSource() = default;

bool VideoFolderSource::next(EncodedStereoPacket& packet) {
  if (interrupted_ || ended_ || index_ >= count_) return false;
  for (std::size_t c = 0; c < 2; ++c) {
    if (demuxers_[c]->read(packet.packets[c])) continue;
    const std::string message =
        fmt::format("{}: video ended after {} frames but data.csv lists {} (truncated or damaged video?)",
                    demuxers_[c]->path().string(), index_, dataset_.frames.size());
    if (options_.strict) throw InputError(message);
    warnings_.push_back(message);
    ended_ = true;
    return false;
  }
  packet.t_ns = dataset_.frames[index_].t_ns;
  packet.frame_index = static_cast<std::int64_t>(index_);
  ++index_;
  return true;
}

std::unique_ptr<StereoSource> openDatasetSource(const Dataset& dataset, const ReplayOptions& options) {
  if (dataset.layout == DatasetLayout::kVocaVideo) return std::make_unique<VideoFolderSource>(dataset, options);
  return std::make_unique<ImageDatasetSource>(dataset, options);
}

}  // namespace voca

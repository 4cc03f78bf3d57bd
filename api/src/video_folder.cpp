#include "voca_rt/video_folder.h"

#include <fmt/core.h>

#include <array>
#include <optional>

#include "api/src/api_internal.h"
#include "drivers/decode/annexb.h"
#include "drivers/source/dataset_source.h"
#include "formats/dataset/dataset.h"

namespace voca_rt {

struct VideoFolderReader::Impl {
  std::optional<voca::VideoFolderSource> source;
  std::array<std::unique_ptr<voca::decode::AnnexBConverter>, 2> converters;
  voca::EncodedStereoPacket packet;
  std::string calibration;
};

VideoFolderReader::VideoFolderReader(const std::string& folder) : impl_(std::make_unique<Impl>()) {
  detail::translated([&] {
    const voca::Dataset dataset = voca::openDataset(folder);
    if (dataset.layout != voca::DatasetLayout::kVocaVideo) {
      throw voca::InputError(fmt::format("{}: a {} folder of images, not a VOCA video folder (mav0/camN/data.mp4)",
                                         folder, voca::layoutName(dataset.layout)));
    }
    if (dataset.calibration) impl_->calibration = dataset.calibration->string();
    impl_->source.emplace(dataset);
    for (std::size_t c = 0; c < 2; ++c) {
      impl_->converters[c] = std::make_unique<voca::decode::AnnexBConverter>(impl_->source->info().streams[c]);
    }
    return 0;
  });
}

VideoFolderReader::~VideoFolderReader() = default;

bool VideoFolderReader::next(StereoPacket& packet) {
  return detail::translated([&] {
    Impl& d = *impl_;
    if (!d.source->next(d.packet)) return false;
    packet.t_ns = d.packet.t_ns;
    packet.frame_index = d.packet.frame_index;
    d.converters[0]->convert(d.packet.packets[0], packet.left);
    d.converters[1]->convert(d.packet.packets[1], packet.right);
    return true;
  });
}

int VideoFolderReader::width() const { return impl_->source->info().width; }
int VideoFolderReader::height() const { return impl_->source->info().height; }
std::int64_t VideoFolderReader::frames() const { return impl_->source->info().expected_frames; }
std::string VideoFolderReader::calibrationFile() const { return impl_->calibration; }

}  // namespace voca_rt

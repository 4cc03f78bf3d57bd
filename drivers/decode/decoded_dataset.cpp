#include "drivers/decode/decoded_dataset.h"

#include <array>

#include <fmt/core.h>

#include "drivers/decode/video_reader.h"
#include "formats/dataset/dataset.h"
#include "voca/core/error.h"

namespace voca::decode {

namespace fs = std::filesystem;

DecodedDatasetReport writeDecodedEuroc(const fs::path& video_folder, const fs::path& out,
                                       const DecodedDatasetProgress& progress) {
  const Dataset dataset = openDataset(video_folder);
  if (dataset.layout != DatasetLayout::kVocaVideo) {
    throw InputError(fmt::format("{}: not a VOCA video folder (mav0/camN/data.mp4)", video_folder.string()));
  }
  DecoderOptions options;
  options.kind = DecoderKind::kSoftware;
  options.export_motion = false;
  options.log_choice = false;
  StereoVideoReader reader(dataset, options);

  DecodedDatasetReport report;
  EurocWriter writer(out);
  DecodedFrame left, right;
  const auto total = static_cast<std::int64_t>(reader.size());
  while (reader.next(left, right)) {
    const std::array<GrayView, 2> images = {left.luma.view(), right.luma.view()};
    writer.addFrame(left.t_ns, images);
    report.width = left.luma.width();
    report.height = left.luma.height();
    if (progress) progress(writer.frameCount(), total);
  }
  writer.finish();
  report.frames = writer.frameCount();

  std::error_code error;
  if (dataset.ground_truth) {
    const fs::path gt = writer.mav0() / "state_groundtruth_estimate0" / "data.csv";
    fs::create_directories(gt.parent_path());
    fs::copy_file(*dataset.ground_truth, gt, fs::copy_options::overwrite_existing, error);
    if (error) throw RuntimeFailure(fmt::format("cannot write {}: {}", gt.string(), error.message()));
    report.ground_truth_copied = true;
  }
  if (dataset.calibration && fs::is_regular_file(*dataset.calibration)) {
    const fs::path calib = out / "calib.json";
    fs::copy_file(*dataset.calibration, calib, fs::copy_options::overwrite_existing, error);
    if (error) throw RuntimeFailure(fmt::format("cannot write {}: {}", calib.string(), error.message()));
    report.calibration_copied = true;
  }
  return report;
}

}  // namespace voca::decode

// Dataset encoding on a small synthetic EuRoC folder: the VOCA video layout, timestamps, re-encoding.

#include <fstream>

#include "drivers/encode/dataset_encoder.h"
#include "formats/dataset/dataset.h"
#include "tests/test_encode_probe.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

using namespace voca;
using namespace voca::encode;

namespace {

// Irregular 20 Hz-ish timestamps with odd nanoseconds, so a round trip through float seconds or
// a re-timed index would show.
std::vector<std::int64_t> makeTimestamps(int n) {
  std::vector<std::int64_t> t;
  std::int64_t now = 1403715273262142976;
  for (int i = 0; i < n; ++i) {
    t.push_back(now);
    now += 50000000 + (i % 3) * 137;
  }
  return t;
}

void writeSyntheticEuroc(const std::filesystem::path& root, const std::vector<std::int64_t>& t, int w, int h) {
  const int n = static_cast<int>(t.size());
  const std::vector<GrayImage> left = test::makePanningSequence(w, h, n, 0.5, 0.25, 3);
  const std::vector<GrayImage> right = test::makePanningSequence(w, h, n, 0.5, 0.25, 4);
  EurocWriter writer(root);
  for (int i = 0; i < n; ++i) {
    const GrayView views[2] = {left[static_cast<std::size_t>(i)].view(), right[static_cast<std::size_t>(i)].view()};
    writer.addFrame(t[static_cast<std::size_t>(i)], views);
  }
  writer.finish();
}

std::vector<std::pair<std::int64_t, std::string>> readCsv(const std::filesystem::path& path, std::string& header) {
  std::ifstream in(path);
  std::getline(in, header);
  std::vector<std::pair<std::int64_t, std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    const auto comma = line.find(',');
    rows.emplace_back(std::stoll(line.substr(0, comma)), line.substr(comma + 1));
  }
  return rows;
}

}  // namespace

TEST_CASE("encodeDataset writes the VOCA video layout with the original timestamps") {
  test::ScratchDir dir("encode-dataset");
  const std::vector<std::int64_t> t = makeTimestamps(24);
  writeSyntheticEuroc(dir / "raw", t, 192, 144);

  DatasetEncodeOptions options;
  options.settings = test::testSettings();
  options.settings.bitrate_bps = 200000;
  std::vector<int> last_frame(2, -1);
  const DatasetEncodeReport report =
      encodeDataset(dir / "raw", dir / "video", options, [&](int camera, int pass, int passes, int frame, int frames) {
        CHECK(passes == 2);
        CHECK(frames == 24);
        if (pass == 2) last_frame.at(static_cast<std::size_t>(camera)) = frame;
      });
  CHECK(last_frame[0] == 23);
  CHECK(last_frame[1] == 23);
  CHECK(report.input_layout == DatasetLayout::kEuroc);
  CHECK(report.num_frames == 24);
  REQUIRE(report.cameras.size() == 2);
  CHECK(report.fps_num == 30);
  // The paper's 30 fps on a 20 Hz dataset: over the dataset's real time the stream takes 2/3 of the
  // achieved (30 fps) bitrate.
  CHECK(report.dataset_fps_num == 20);
  CHECK(report.dataset_fps_den == 1);
  CHECK(report.realTimeRateScale() == doctest::Approx(20.0 / 30.0));
  CHECK_FALSE(report.timedAtDatasetRate());
  CHECK(report.raw_bytes == 2 * 24 * 192 * 144);
  CHECK(report.output_bytes > 0);
  CHECK(report.input_bytes > report.output_bytes);

  for (int camera : {0, 1}) {
    const auto cam_dir = dir.path() / "video" / "mav0" / ("cam" + std::to_string(camera));
    const test::VideoProbe probe = test::probeVideo(cam_dir / "data.mp4");
    CHECK(probe.codec_name == "h264");
    CHECK(probe.width == 192);
    CHECK(probe.height == 144);
    CHECK(probe.picture_types.size() == t.size());
    std::string header;
    const auto rows = readCsv(cam_dir / "data.csv", header);
    CHECK(header == "#timestamp [ns],filename");
    REQUIRE(rows.size() == t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
      CHECK(rows[i].first == t[i]);  // exact: the nanoseconds are copied, never converted
      CHECK(rows[i].second == std::to_string(t[i]) + ".png");
    }
  }

  // The result is a dataset our reader recognises, with the same frame times.
  const Dataset video = openDataset(dir / "video");
  CHECK(video.layout == DatasetLayout::kVocaVideo);
  REQUIRE(video.frames.size() == t.size());
  for (std::size_t i = 0; i < t.size(); ++i) CHECK(video.frames[i].t_ns == t[i]);

  // Re-encoding a VOCA video folder at another bitrate and the dataset's own rate (20 Hz).
  DatasetEncodeOptions again;
  again.settings = test::testSettings();
  again.settings.bitrate_bps = 100000;
  again.use_dataset_fps = true;
  again.cameras = {1};
  const DatasetEncodeReport second = encodeDataset(dir / "video", dir / "video2", again);
  CHECK(second.input_layout == DatasetLayout::kVocaVideo);
  CHECK(second.fps_num == 20);
  CHECK(second.fps_den == 1);
  CHECK(second.realTimeRateScale() == 1.0);
  CHECK(second.timedAtDatasetRate());
  REQUIRE(second.cameras.size() == 1);
  const test::VideoProbe probe = test::probeVideo(dir.path() / "video2" / "mav0" / "cam1" / "data.mp4");
  CHECK(probe.picture_types.size() == t.size());
  CHECK(av_cmp_q(probe.avg_frame_rate, AVRational{20, 1}) == 0);
  // 24 frames at 20 fps = 1.2 s; two-pass keeps the total within 15 % as in the file-encoder test.
  CHECK(second.cameras[0].result.achieved_bitrate_bps == doctest::Approx(100000.0).epsilon(0.15));
  std::string header;
  const auto rows = readCsv(dir.path() / "video2" / "mav0" / "cam1" / "data.csv", header);
  REQUIRE(rows.size() == t.size());
  CHECK(rows.back().first == t.back());
}

TEST_CASE("datasetFrameRate rounds to whole rates and keeps fractional ones") {
  Dataset dataset;
  for (int i = 0; i < 10; ++i) dataset.frames.push_back({i * 50000000LL + (i % 2), {}, {}});
  int num = 0, den = 0;
  datasetFrameRate(dataset, num, den);
  CHECK(num == 20);
  CHECK(den == 1);
  dataset.frames.clear();
  // 1001/30000 s per frame: NTSC 29.97 Hz, exactly as MPEG-2 lists it.
  for (int i = 0; i < 10; ++i) dataset.frames.push_back({i * 33366667LL, {}, {}});
  datasetFrameRate(dataset, num, den);
  CHECK(num == 30000);
  CHECK(den == 1001);
  dataset.frames.clear();
  // KITTI-like 9.65 Hz: neither, kept to the millihertz (9650/1000 = 193/20).
  for (int i = 0; i < 10; ++i) dataset.frames.push_back({i * 103626943LL, {}, {}});
  datasetFrameRate(dataset, num, den);
  CHECK(num == 193);
  CHECK(den == 20);
}

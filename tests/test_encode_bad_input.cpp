// Encoder and `voca encode` logic on bad input: clear InputErrors, no crash, no half-written files.

#include <fstream>
#include <iterator>
#include <map>

#include "drivers/encode/dataset_encoder.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "formats/calib/calibration_io.h"
#include "formats/dataset/dataset.h"
#include "formats/image/png_io.h"
#include "tests/test_encode_probe.h"
#include "tests/test_support.h"
#include "voca/core/error.h"
#include "voca/synth/rigs.h"

using namespace voca;
using namespace voca::encode;

namespace {

std::string inputErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no InputError>";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

FrameSource framesOfSizes(std::vector<std::pair<int, int>> sizes) {
  return [sizes](const std::function<void(GrayView)>& emit) {
    for (const auto& [w, h] : sizes) {
      GrayImage image(w, h, 100);
      emit(image.view());
    }
  };
}

// The test encoder's settings in one pass: quick dataset encodings.
DatasetEncodeOptions singlePassOptions() {
  DatasetEncodeOptions options;
  options.settings = test::testSettings();
  options.settings.two_pass = false;
  return options;
}

}  // namespace

TEST_CASE("bad bitrate strings are InputErrors naming the text") {
  for (const char* text : {"abc", "", "k", "-500k", "0", "500kb", "1e6", "5 00k", "1.2.3M", ".", "10"}) {
    CAPTURE(text);
    const std::string message = inputErrorOf([&] { parseBitrate(text); });
    CHECK(contains(message, "bitrate"));
    CHECK(contains(message, std::string("'") + text + "'"));
  }
}

TEST_CASE("frames of different sizes stop the encode and leave no file") {
  test::ScratchDir dir("encode-bad-sizes");
  const auto path = dir / "v.mp4";
  EncoderSettings settings = test::testSettings();
  const std::string message = inputErrorOf([&] {
    encodeVideoFile(path, settings, framesOfSizes({{64, 48}, {64, 48}, {80, 48}}));
  });
  CHECK(contains(message, "80x48"));
  CHECK(contains(message, "64x48"));
  CHECK(!std::filesystem::exists(path));
}

TEST_CASE("encoder settings and outputs that cannot work are InputErrors") {
  test::ScratchDir dir("encode-bad-settings");
  EncoderSettings settings = test::testSettings();
  settings.two_pass = false;
  const FrameSource three = framesOfSizes({{64, 48}, {64, 48}, {64, 48}});

  CHECK(contains(inputErrorOf([&] { encodeVideoFile(dir / "none.mp4", settings, framesOfSizes({})); }), "no frames"));
  CHECK(!std::filesystem::exists(dir / "none.mp4"));
  CHECK(contains(inputErrorOf([&] { encodeVideoFile(dir / "missing" / "sub" / "v.mp4", settings, three); }),
                 "cannot write"));

  EncoderSettings codec = settings;
  codec.codec = "libx265";
  CHECK(contains(inputErrorOf([&] { encodeVideoFile(dir / "a.mp4", codec, three); }), "libx265"));

  EncoderSettings rate = settings;
  rate.codec = "mpeg2video";
  rate.fps_num = 23;  // MPEG-2 only has the standard rates
  CHECK(contains(inputErrorOf([&] { encodeVideoFile(dir / "b.mp4", rate, three); }), "23/1"));

  EncoderSettings params = settings;
  params.x264_params = "keyint=1000:no-such-option=3";
  CHECK(!inputErrorOf([&] { encodeVideoFile(dir / "c.mp4", params, three); }).empty());

  CHECK(contains(inputErrorOf([&] { encodeVideoFile(dir / "d.mp4", settings, framesOfSizes({{8, 8}})); }), "8x8"));

  VideoEncoder encoder;
  encoder.open(settings, 64, 48);
  GrayImage wrong(32, 48, 0);
  CHECK(contains(inputErrorOf([&] { encoder.encode(wrong.view(), 0); }), "32x48"));
}

TEST_CASE("an MPEG second pass that cannot reach the bitrate is an InputError, not a heap corruption") {
  // libavcodec 5.1 frees the rate control twice when mpegvideo's second pass refuses the bitrate;
  // the encoder tries that open in a forked copy first, so this process lives to report it.
  test::ScratchDir dir("encode-bad-pass2");
  // Noise: the first pass codes every block with vectors and headers that 2 kbit/s cannot hold.
  std::vector<GrayImage> frames;
  std::uint32_t state = 12345;
  for (int f = 0; f < 20; ++f) {
    GrayImage image(160, 120, 0);
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        state = state * 1664525u + 1013904223u;
        image(x, y) = static_cast<std::uint8_t>(state >> 24);
      }
    frames.push_back(std::move(image));
  }
  const FrameSource noise = [&](const std::function<void(GrayView)>& emit) {
    for (const GrayImage& image : frames) emit(image.view());
  };
  for (const char* codec_name : {"mpeg2video", "mpeg4"}) {
    CAPTURE(codec_name);
    EncoderSettings settings = test::testSettings();
    settings.codec = codec_name;
    settings.two_pass = true;
    settings.bitrate_bps = 2000;
    const std::string message = inputErrorOf([&] { encodeVideoFile(dir / "v.mp4", settings, noise); });
    CHECK(contains(message, codec_name));
    CHECK(contains(message, "two passes"));
    CHECK(contains(message, "bitrate"));  // libavcodec's own reason
    CHECK(!std::filesystem::exists(dir / "v.mp4"));
    // The same clip at a bitrate it can reach still encodes in two passes.
    settings.bitrate_bps = 4000000;
    CHECK(encodeVideoFile(dir / "ok.mp4", settings, noise).achieved_bitrate_bps > 0.0);
  }
}

TEST_CASE("dataset problems are InputErrors naming the folder") {
  test::ScratchDir dir("encode-bad-dataset");
  DatasetEncodeOptions options = singlePassOptions();

  const auto missing = dir / "no-such-dataset";
  CHECK(contains(inputErrorOf([&] { encodeDataset(missing, dir / "out", options); }), missing.string()));

  std::filesystem::create_directories(dir / "empty");
  CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "empty", dir / "out", options); }), "unknown dataset layout"));

  // A tiny valid EuRoC folder to break in other ways.
  {
    EurocWriter writer(dir / "raw");
    GrayImage image(64, 48, 90);
    const GrayView views[2] = {image.view(), image.view()};
    for (std::int64_t t : {1000000000LL, 1050000000LL, 1100000000LL}) writer.addFrame(t, views);
    writer.finish();
  }
  DatasetEncodeOptions cameras = options;
  cameras.cameras = {0, 2};
  CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "raw", dir / "out", cameras); }), "camera 2"));
  CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "raw", dir / "raw", options); }), "input dataset"));

  // Settings the codec cannot take fail before anything is written.
  DatasetEncodeOptions rate = options;
  rate.settings.codec = "mpeg2video";
  rate.settings.fps_num = 23;
  CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "raw", dir / "out-rate", rate); }), "23/1"));
  CHECK(!std::filesystem::exists(dir / "out-rate"));

  // The output folder cannot be created where a file is.
  std::ofstream(dir / "file-not-folder") << "x";
  CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "raw", dir / "file-not-folder", options); }),
                 "cannot create the output folder"));

  // A missing --calib file fails before any encoding.
  DatasetEncodeOptions calib = options;
  calib.calibration = dir / "nope.json";
  CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "raw", dir / "out-calib", calib); }), "nope.json"));
  CHECK(!std::filesystem::exists(dir / "out-calib" / "mav0" / "cam0" / "data.mp4"));
  // A calibration for another image size fails before any encoding too: `voca run` refused the folder.
  saveBasaltCalibration(synth::eurocRig(), dir / "calib-752x480.json");
  calib.calibration = dir / "calib-752x480.json";
  const std::string other_size = inputErrorOf([&] { encodeDataset(dir / "raw", dir / "out-calib-size", calib); });
  CHECK(contains(other_size, "calib-752x480.json: camera 0 is calibrated for 752x480 images, but "));
  CHECK(contains(other_size, "is 64x48"));
  CHECK(!std::filesystem::exists(dir / "out-calib-size"));

  // A corrupt PNG is reported with its file name and frame, and the folder the run made is gone.
  const Dataset raw = openDataset(dir / "raw");
  std::ofstream(raw.frames[1].left, std::ios::binary | std::ios::trunc) << "not a png";
  const std::string corrupt = inputErrorOf([&] { encodeDataset(dir / "raw", dir / "out-png", options); });
  CHECK(contains(corrupt, raw.frames[1].left.string() + ": not a PNG file"));
  CHECK(contains(corrupt, "(frame 1 of cam0)"));
  CHECK(!std::filesystem::exists(dir / "out-png"));

  // An image of another size within one camera.
  writePngGray(raw.frames[1].left, GrayImage(80, 48, 90).view());
  const std::string size = inputErrorOf([&] { encodeDataset(dir / "raw", dir / "out-size", options); });
  CHECK(contains(size, raw.frames[1].left.string() + ": 80x48 pixels, but the camera's first image is 64x48"));
  CHECK(!std::filesystem::exists(dir / "out-size" / "mav0" / "cam0" / "data.mp4"));
}

TEST_CASE("a failed dataset encoding removes what it created and only that; its warnings still arrive") {
  namespace fs = std::filesystem;
  test::ScratchDir dir("encode-cleanup");
  DatasetEncodeOptions options = singlePassOptions();
  {
    EurocWriter writer(dir / "raw");
    GrayImage image(64, 48, 90);
    const GrayView views[2] = {image.view(), image.view()};
    for (std::int64_t t = 1; t <= 5; ++t) writer.addFrame(t * 50000000LL, views);
    writer.finish();
  }
  const Dataset raw = openDataset(dir / "raw");
  // Frame 1's right image is missing (that frame is left out with a warning), frame 3's cam1 image
  // is corrupt: cam0 encodes, cam1 fails.
  fs::remove(raw.frames[1].right);
  std::ofstream(raw.frames[3].right, std::ios::binary | std::ios::trunc) << "not a png";

  // The warnings come through the callback before the encoding starts, so a failed run shows them.
  std::vector<std::string> warnings;
  const auto collect = [&](const std::string& warning) { warnings.push_back(warning); };
  const std::string error = inputErrorOf([&] { encodeDataset(dir / "raw", dir / "new", options, {}, collect); });
  CHECK(contains(error, raw.frames[3].right.string()));
  CHECK(contains(error, "of cam1"));
  REQUIRE(warnings.size() == 2);
  CHECK(contains(warnings[0], "1 of 5 rows have no image file and were skipped (data/100000000.png)"));
  CHECK(contains(warnings[1], "1 cam0 images have no cam1 image"));
  // The run created the folder: nothing of it is left, not even cam0's finished video.
  CHECK(!fs::exists(dir / "new"));

  // Into a folder the user already has: their files stay, the run's own additions go.
  const fs::path user = dir / "user";
  fs::create_directories(user / "mav0" / "imu0");
  std::ofstream(user / "notes.txt") << "mine";
  std::ofstream(user / "mav0" / "imu0" / "data.csv") << "mine too";
  CHECK(!inputErrorOf([&] { encodeDataset(dir / "raw", user, options); }).empty());
  CHECK(fs::exists(user / "notes.txt"));
  CHECK(fs::exists(user / "mav0" / "imu0" / "data.csv"));
  CHECK(!fs::exists(user / "mav0" / "cam0"));
  CHECK(!fs::exists(user / "mav0" / "cam1"));
  CHECK(!fs::exists(user / "calib.json"));

  // The same folder and dataset, repaired: the encoding succeeds and keeps its output.
  fs::remove(raw.frames[3].right);
  const DatasetEncodeReport report = encodeDataset(dir / "raw", user, options, {}, collect);
  CHECK(report.num_frames == 3);
  CHECK(fs::exists(user / "mav0" / "cam1" / "data.mp4"));
  CHECK(fs::exists(user / "notes.txt"));
}

TEST_CASE("a re-encoding that fails or is stopped leaves the previous encoding as it was") {
  namespace fs = std::filesystem;
  test::ScratchDir dir("encode-replace");
  DatasetEncodeOptions options = singlePassOptions();
  {
    EurocWriter writer(dir / "raw");
    for (std::int64_t t = 1; t <= 6; ++t) {
      GrayImage image(64, 48, static_cast<std::uint8_t>(40 + 20 * t));
      const GrayView views[2] = {image.view(), image.view()};
      writer.addFrame(t * 50000000LL, views);
    }
    writer.finish();
  }
  const fs::path out = dir / "out";
  REQUIRE(!encodeDataset(dir / "raw", out, options).stopped);
  // Every file of the encoding, with its bytes.
  const auto snapshot = [&] {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(out)) {
      if (!entry.is_regular_file()) continue;
      std::ifstream in(entry.path(), std::ios::binary);
      files[fs::relative(entry.path(), out).string()] =
          std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    return files;
  };
  const auto before = snapshot();
  REQUIRE(before.count("mav0/cam0/data.mp4") == 1);
  REQUIRE(before.count("mav0/cam1/data.csv") == 1);

  SUBCASE("stopped half way through the second camera") {
    options.settings.bitrate_bps *= 2;  // another encoding, so overwritten files would differ
    int frames_seen = 0;
    options.stop_requested = [&] { return ++frames_seen > 9; };
    const DatasetEncodeReport report = encodeDataset(dir / "raw", out, options);
    CHECK(report.stopped);
    CHECK(report.cameras.empty());
    CHECK(frames_seen == 10);
  }
  SUBCASE("failing at cam1's fourth image") {
    options.settings.bitrate_bps *= 2;
    std::ofstream(openDataset(dir / "raw").frames[3].right, std::ios::binary | std::ios::trunc) << "not a png";
    CHECK(contains(inputErrorOf([&] { encodeDataset(dir / "raw", out, options); }), "of cam1"));
  }
  // The same files with the same bytes, and no temporary file beside them.
  CHECK(snapshot() == before);

  // A stopped first encoding leaves no folder.
  options.stop_requested = [] { return true; };
  CHECK(encodeDataset(dir / "raw", dir / "fresh", options).stopped);
  CHECK(!fs::exists(dir / "fresh"));
}

// End to end through the `voca` binary: synth -> encode -> `voca mv`, checking that the pictures of
// what the codec saw are written, sized like the video, and carry vectors on P-frames only.

#include <fstream>
#include <iterator>
#include <string>

#include "drivers/decode/demuxer.h"
#include "drivers/encode/rgb_video_writer.h"
#include "formats/image/png_io.h"
#include "tests/test_support.h"
#include "tests/test_video_damage.h"

namespace fs = std::filesystem;

namespace {

using voca::test::runVoca;

// Pixels where the picture is not gray: the coloured partitions, arrows and outlier marks.
long colouredPixels(const fs::path& png) {
  voca::RgbImage image;
  voca::readPngRgb(png, image);
  long coloured = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const voca::Rgb8 p = image(x, y);
      coloured += (p.r != p.g || p.g != p.b) ? 1 : 0;
    }
  }
  return coloured;
}

// `voca synth <synth_args>` into dir/raw, encoded at 500 kbit/s in one pass into dir/video.
fs::path renderAndEncode(const voca::test::ScratchDir& dir, const std::string& synth_args) {
  const fs::path raw = dir / "raw", video = dir / "video";
  REQUIRE(runVoca("synth --out " + raw.string() + " " + synth_args + " --threads 2") == 0);
  REQUIRE(runVoca("encode " + raw.string() + " --out " + video.string() + " --bitrate 500k --single-pass") == 0);
  return video;
}

// The video packets of a file: its frames, when its index was written.
int packetCount(const fs::path& video) {
  voca::decode::Demuxer demuxer(video);
  voca::decode::Packet packet;
  int packets = 0;
  while (demuxer.read(packet)) ++packets;
  return packets;
}

}  // namespace

TEST_CASE("voca mv draws the codec's vectors on P-frames, as PNGs and as an mp4") {
  voca::test::ScratchDir dir("mv-cli");
  const fs::path raw = dir / "raw";
  // 8 frames of fast rotation: tens of pixels of motion, so every P-frame has many inter blocks.
  const fs::path video = renderAndEncode(dir, "--seconds 0.4 --motion fast-rotation");

  const fs::path pngs = dir / "png";
  REQUIRE(runVoca("mv " + video.string() + " --out " + pngs.string() + " --frames 0:6") == 0);
  for (int frame = 0; frame < 6; ++frame) {
    const fs::path png = pngs / ("mv_00000" + std::to_string(frame) + ".png");
    CAPTURE(png.string());
    REQUIRE(fs::exists(png));
    voca::GrayImage gray;
    voca::readPngGray(png, gray);
    CHECK(gray.width() == 752);
    CHECK(gray.height() == 480);
  }
  CHECK_FALSE(fs::exists(pngs / "mv_000006.png"));  // the range end is exclusive
  // Frame 0 is the I-frame: no vectors, so nothing coloured; P-frames carry partitions and arrows
  // over a good part of the picture (at least 1 % of the pixels).
  CHECK(colouredPixels(pngs / "mv_000000.png") == 0);
  for (int frame = 1; frame < 6; ++frame)
    CHECK(colouredPixels(pngs / ("mv_00000" + std::to_string(frame) + ".png")) > 752 * 480 / 100);

  const fs::path mp4 = dir / "mp4";
  REQUIRE(runVoca("mv " + video.string() + " --out " + mp4.string() + " --format mp4 --camera 1") == 0);
  CHECK(voca::decode::Demuxer(mp4 / "mv.mp4").stream().width == 752);
  CHECK(voca::decode::Demuxer(mp4 / "mv.mp4").stream().height == 480);
  CHECK(packetCount(mp4 / "mv.mp4") == 8);

  // A damaged picture is drawn as the decoder concealed it and named; --strict stops there instead.
  voca::test::damagePacket(video / "mav0" / "cam0" / "data.mp4", 3);
  const auto damaged = voca::test::runVocaOutput("mv " + video.string() + " --out " + (dir / "damaged").string());
  CAPTURE(damaged.text);
  CHECK(damaged.exit_code == 0);
  CHECK(damaged.text.find("warning: frame 3 is damaged") != std::string::npos);
  CHECK(damaged.text.find("wrote 8 frame(s)") != std::string::npos);
  CHECK(damaged.text.find("; 1 damaged)") != std::string::npos);
  CHECK(fs::exists(dir / "damaged" / "mv_000007.png"));
  const auto strict =
      voca::test::runVocaOutput("mv " + video.string() + " --out " + (dir / "strict").string() + " --strict");
  CAPTURE(strict.text);
  CHECK(strict.exit_code == 1);
  CHECK(strict.text.find("frame 3") != std::string::npos);

  // Bad input: a folder that is not a video dataset, and a camera that does not exist.
  CHECK(runVoca("mv " + raw.string() + " --out " + (dir / "bad1").string()) != 0);
  CHECK(runVoca("mv " + video.string() + " --out " + (dir / "bad2").string() + " --camera 2") != 0);
  // Values that changed the drawing silently (a negative radius flagged more vectors) are refused by name.
  for (const std::string option : {"--outlier-radius -5", "--outlier-radius 0", "--outlier-threshold -1",
                                   "--outlier-relative -0.5", "--arrow-scale 0", "--arrow-scale -1"}) {
    const voca::test::CommandOutput bad =
        voca::test::runVocaOutput("mv " + video.string() + " --out " + (dir / "bad3").string() + " " + option);
    INFO(option);
    INFO(bad.text);
    CHECK(bad.exit_code == 1);
    CHECK(bad.text.find(option + ": expected") != std::string::npos);
  }
  CHECK_FALSE(fs::exists(dir / "bad3"));

  // One camera encoded (`voca encode --cameras 1`): mv draws it; run names the missing left video.
  const fs::path right_only = dir / "right-only";
  REQUIRE(runVoca("encode " + raw.string() + " --out " + right_only.string() + " --cameras 1 --single-pass") == 0);
  REQUIRE(runVoca("mv " + right_only.string() + " --camera 1 -o " + (dir / "right").string() + " --frames 1:2") == 0);
  CHECK(fs::exists(dir / "right" / "mv_000001.png"));
  const voca::test::CommandOutput run =
      voca::test::runVocaOutput("run " + right_only.string() + " -o " + (dir / "t.txt").string());
  INFO(run.text);
  CHECK(run.exit_code == 1);
  CHECK(run.text.find("cam0/data.mp4: missing (the VOCA video layout needs cam0 and cam1 videos; this folder holds "
                      "cam1's alone)") != std::string::npos);
}

TEST_CASE("RgbVideoWriter opens its file at once; without a frame it leaves none behind") {
  voca::test::ScratchDir dir("rgb-writer");
  const std::string error =
      voca::test::inputErrorOf([&] { voca::encode::RgbVideoWriter writer(dir / "no-such-folder" / "x.mp4"); });
  CHECK(error.find("no-such-folder/x.mp4: cannot open for writing") != std::string::npos);
  {
    voca::encode::RgbVideoWriter writer(dir / "empty.mp4");
    CHECK(fs::exists(dir / "empty.mp4"));
  }
  CHECK_FALSE(fs::exists(dir / "empty.mp4"));
}

TEST_CASE("voca track --overlay: the tracks as an mp4; an unwritable path fails before tracking, naming it") {
  voca::test::ScratchDir dir("track-overlay");
  const fs::path raw = dir / "raw";
  const fs::path video = dir / "video";
  REQUIRE(runVoca("synth --out " + raw.string() + " --seconds 0.3 --motion gentle --supersample 1") == 0);
  REQUIRE(runVoca("encode " + raw.string() + " --out " + video.string() + " --bitrate 500k --single-pass") == 0);

  const fs::path overlay = dir / "overlay.mp4";
  const auto ok = voca::test::runVocaOutput("track " + video.string() + " --overlay " + overlay.string());
  CAPTURE(ok.text);
  REQUIRE(ok.exit_code == 0);
  CHECK(ok.text.find("overlay: " + overlay.string()) != std::string::npos);
  voca::decode::Demuxer demuxer(overlay);
  CHECK(demuxer.stream().width == 752);
  voca::decode::Packet packet;
  int packets = 0;
  while (demuxer.read(packet)) ++packets;
  CHECK(packets == 6);

  const fs::path unwritable = dir / "no-such-folder" / "overlay.mp4";
  const auto bad = voca::test::runVocaOutput("track " + video.string() + " --overlay " + unwritable.string());
  CAPTURE(bad.text);
  CHECK(bad.exit_code == 1);
  CHECK(bad.text.find("cannot write the overlay video " + unwritable.string() + ": the folder " +
                      (dir / "no-such-folder").string() + " does not exist") != std::string::npos);
  CHECK(bad.text.find("tracks per frame") == std::string::npos);  // no summary of a run that did not happen
  CHECK(bad.text.find("overlay: ") == std::string::npos);
}

TEST_CASE("voca mv stopped by a signal closes its mp4 properly: it plays the frames drawn so far") {
  voca::test::ScratchDir dir("mv-signal");
  const fs::path video = renderAndEncode(dir, "--seconds 3 --supersample 1");
  const fs::path out = dir / "mp4";
  const fs::path log = dir / "log.txt";
  const pid_t pid =
      voca::test::spawnVoca("mv " + video.string() + " --out " + out.string() + " --format mp4", dir.path(), log);
  // Bytes in the file: the first frames are drawn (the writer creates it empty at the start).
  REQUIRE(voca::test::signalWhenWritten(pid, out / "mv.mp4", SIGINT));
  const int exit_code = voca::test::waitExitCode(pid);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CAPTURE(text);
  CHECK(exit_code == 130);
  const std::size_t said = text.find("stopped by a signal after ");
  REQUIRE(said != std::string::npos);
  const int drawn = std::stoi(text.substr(said + std::string("stopped by a signal after ").size()));
  CHECK(drawn >= 1);
  CHECK(drawn < 60);
  // The index was written: the file opens and holds exactly those frames.
  CHECK(packetCount(out / "mv.mp4") == drawn);
}

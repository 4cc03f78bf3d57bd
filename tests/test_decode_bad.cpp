// Bad input for the decoder: truncated and random files, unsupported streams, a missing camera,
// mismatched frame counts and corrupt packets must give voca::InputError with a clear message
// (file, frame or packet index), never a crash or a hang. Runs under AddressSanitizer in CI.

#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "drivers/decode/video_reader.h"
#include "drivers/encode/video_encoder.h"
#include "drivers/encode/video_file_encoder.h"
#include "formats/dataset/dataset.h"
#include "test_support.h"
#include "voca/core/error.h"

namespace {

namespace fs = std::filesystem;
using voca::decode::DecodedFrame;
using voca::decode::VideoReader;

constexpr int kWidth = 96, kHeight = 64;

// Noise texture drifting one pixel per frame: every P-frame has vectors.
void encodeClip(const fs::path& path, int frames) {
  voca::encode::EncoderSettings settings;
  settings.two_pass = false;  // speed; the stream structure is what matters here
  voca::encode::encodeVideoFile(path, settings, [&](const std::function<void(voca::GrayView)>& emit) {
    std::mt19937 rng(1);
    std::vector<std::uint8_t> noise(static_cast<std::size_t>((kWidth + frames) * kHeight));
    for (auto& v : noise) v = static_cast<std::uint8_t>(rng() % 200 + 20);
    voca::GrayImage image(kWidth, kHeight);
    for (int k = 0; k < frames; ++k) {
      for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
          image(x, y) = noise[static_cast<std::size_t>(y * (kWidth + frames) + x + frames - k)];
      emit(image.view());
    }
  });
}

std::vector<std::uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const fs::path& path, const std::vector<std::uint8_t>& bytes, std::size_t count) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(count));
}

std::vector<std::int64_t> timestamps(int n) {
  std::vector<std::int64_t> t;
  for (int i = 0; i < n; ++i) t.push_back(1000000000LL + 50000000LL * i);
  return t;
}

// Decodes a whole file; returns the number of frames.
int readAll(const fs::path& path, std::vector<std::int64_t> t_ns = {}) {
  voca::decode::DecoderOptions options;
  options.kind = voca::decode::DecoderKind::kSoftware;
  VideoReader reader(path, std::move(t_ns), options);
  DecodedFrame frame;
  int n = 0;
  while (reader.next(frame)) ++n;
  return n;
}

using voca::test::inputErrorOf;

void writeCsv(const fs::path& path, int rows) {
  std::ofstream csv(path);
  csv << "#timestamp [ns],filename\n";
  for (std::int64_t t : timestamps(rows)) csv << t << "," << t << ".png\n";
}

}  // namespace

TEST_CASE("a good clip decodes (baseline for the damaged copies below)") {
  voca::test::ScratchDir dir("decode-bad-good");
  encodeClip(dir / "good.mp4", 8);
  CHECK(readAll(dir / "good.mp4", timestamps(8)) == 8);
}

TEST_CASE("truncated mp4 files are reported, naming the file") {
  voca::test::ScratchDir dir("decode-bad-truncated");
  encodeClip(dir / "good.mp4", 8);
  const std::vector<std::uint8_t> bytes = readBytes(dir / "good.mp4");
  REQUIRE(bytes.size() > 200);
  // The index (moov) is at the end of our files, so these cuts lose it or the samples it points to.
  for (const double keep : {0.05, 0.5, 0.9}) {
    CAPTURE(keep);
    const fs::path cut = dir / "cut.mp4";
    writeBytes(cut, bytes, static_cast<std::size_t>(keep * static_cast<double>(bytes.size())));
    const std::string message = inputErrorOf([&] { readAll(cut, timestamps(8)); });
    CHECK(message.find("cut.mp4") != std::string::npos);
  }
}

// Rewrites the first `count` packets of an H.264 mp4 as a raw Annex-B stream (SPS/PPS from the avcC
// header, start codes instead of length prefixes): a file without an index, cut after `count` frames.
void writeRawH264(const fs::path& mp4, const fs::path& out, std::size_t count) {
  voca::decode::Demuxer demuxer(mp4);
  const std::vector<std::uint8_t>& avcc = demuxer.stream().extradata;
  REQUIRE(avcc.size() > 8);
  std::vector<std::uint8_t> raw;
  const std::uint8_t start[4] = {0, 0, 0, 1};
  std::size_t pos = 5;
  for (int set = 0; set < 2; ++set) {  // SPS list then PPS list
    const int n = set == 0 ? (avcc[pos++] & 0x1f) : avcc[pos++];
    for (int i = 0; i < n; ++i) {
      const std::size_t len = std::size_t(avcc[pos]) << 8 | avcc[pos + 1];
      pos += 2;
      raw.insert(raw.end(), start, start + 4);
      raw.insert(raw.end(), avcc.begin() + long(pos), avcc.begin() + long(pos + len));
      pos += len;
    }
  }
  voca::decode::Packet packet;
  for (std::size_t k = 0; k < count && demuxer.read(packet); ++k) {
    for (std::size_t p = 0; p + 4 <= packet.bytes.size();) {
      const std::size_t len = std::size_t(packet.bytes[p]) << 24 | std::size_t(packet.bytes[p + 1]) << 16 |
                              std::size_t(packet.bytes[p + 2]) << 8 | packet.bytes[p + 3];
      raw.insert(raw.end(), start, start + 4);
      raw.insert(raw.end(), packet.bytes.begin() + long(p + 4), packet.bytes.begin() + long(p + 4 + len));
      p += 4 + len;
    }
  }
  writeBytes(out, raw, raw.size());
}

TEST_CASE("a stream cut after some frames, without an index to tell, is reported at its end") {
  voca::test::ScratchDir dir("decode-bad-raw");
  encodeClip(dir / "good.mp4", 8);
  writeRawH264(dir / "good.mp4", dir / "whole.h264", 8);
  writeRawH264(dir / "good.mp4", dir / "cut.h264", 5);
  CHECK(readAll(dir / "whole.h264", timestamps(8)) == 8);  // the conversion itself is sound
  const std::string message = inputErrorOf([&] { readAll(dir / "cut.h264", timestamps(8)); });
  CHECK(message.find("cut.h264") != std::string::npos);
  CHECK(message.find("after 5 frames") != std::string::npos);
}

TEST_CASE("random bytes, empty files, missing files and non-video files are reported") {
  voca::test::ScratchDir dir("decode-bad-random");
  std::mt19937 rng(42);
  std::vector<std::uint8_t> noise(20000);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  writeBytes(dir / "noise.mp4", noise, noise.size());
  writeBytes(dir / "empty.mp4", noise, 0);
  // A text file: libavformat may probe it as some format, but it is no supported video.
  {
    std::ofstream text(dir / "notes.mp4");
    text << "not a video\n";
  }
  for (const char* name : {"noise.mp4", "empty.mp4", "notes.mp4", "absent.mp4"}) {
    CAPTURE(name);
    const std::string message = inputErrorOf([&] { readAll(dir / name); });
    CHECK(message.find(name) != std::string::npos);
  }
  // What is there but no file says what it is (a device was read without end before).
  CHECK(inputErrorOf([&] {
          voca::decode::Demuxer demuxer(dir / "absent.mp4");
        }).ends_with("absent.mp4: no such video file"));
  CHECK(inputErrorOf([&] { voca::decode::Demuxer demuxer(dir.path()); }).ends_with(": a folder, not a video file"));
  CHECK(inputErrorOf([&] { voca::decode::Demuxer demuxer("/dev/zero"); }) ==
        "/dev/zero: not a regular file (a device or a pipe), not a video file");
}

TEST_CASE("a stereo dataset with a missing camera stream is reported") {
  voca::test::ScratchDir dir("decode-bad-missing");
  fs::create_directories(dir / "mav0" / "cam0");
  fs::create_directories(dir / "mav0" / "cam1");
  encodeClip(dir / "mav0" / "cam0" / "data.mp4", 6);
  writeCsv(dir / "mav0" / "cam0" / "data.csv", 6);
  writeCsv(dir / "mav0" / "cam1" / "data.csv", 6);
  // Through the dataset reader ...
  CHECK(inputErrorOf([&] { (void)voca::openDataset(dir.path()); }).find("cam1") != std::string::npos);
  // ... and with explicit files.
  const std::string message = inputErrorOf([&] {
    voca::decode::StereoVideoReader reader(dir / "mav0" / "cam0" / "data.mp4", dir / "mav0" / "cam1" / "data.mp4",
                                           timestamps(6));
  });
  CHECK(message.find("cam1") != std::string::npos);
  CHECK(message.find("no such video file") != std::string::npos);
}

TEST_CASE("mismatched frame counts between cameras and data.csv are reported") {
  voca::test::ScratchDir dir("decode-bad-counts");
  const fs::path mav0 = dir / "mav0";
  fs::create_directories(mav0 / "cam0");
  fs::create_directories(mav0 / "cam1");
  encodeClip(mav0 / "cam0" / "data.mp4", 8);
  encodeClip(mav0 / "cam1" / "data.mp4", 6);

  SUBCASE("cameras differ") {
    writeCsv(mav0 / "cam0" / "data.csv", 8);
    writeCsv(mav0 / "cam1" / "data.csv", 8);
    const std::string message =
        inputErrorOf([&] { voca::decode::StereoVideoReader reader(voca::openDataset(dir.path())); });
    CHECK(message.find("cam1") != std::string::npos);
    CHECK(message.find("6 frames") != std::string::npos);
  }
  SUBCASE("csv lists fewer frames than the video has") {
    const std::string message = inputErrorOf([&] { readAll(mav0 / "cam0" / "data.mp4", timestamps(7)); });
    CHECK(message.find("8 frames") != std::string::npos);
    CHECK(message.find("7 timestamps") != std::string::npos);
  }
  SUBCASE("csv lists more frames than the video has") {
    const std::string message = inputErrorOf([&] { readAll(mav0 / "cam1" / "data.mp4", timestamps(9)); });
    CHECK(message.find("cam1") != std::string::npos);
    CHECK(message.find("9 timestamps") != std::string::npos);
  }
}

TEST_CASE("corrupt packets are reported with their index") {
  voca::test::ScratchDir dir("decode-bad-corrupt");
  encodeClip(dir / "good.mp4", 8);
  voca::decode::Demuxer demuxer(dir / "good.mp4");
  std::vector<voca::decode::Packet> packets = voca::decode::readAllPackets(demuxer);
  REQUIRE(packets.size() == 8);
  std::mt19937 rng(3);
  // Overwrite packet 3 after its first NAL header bytes with noise: the slice data becomes garbage.
  for (std::size_t i = 8; i < packets[3].bytes.size(); ++i) packets[3].bytes[i] = static_cast<std::uint8_t>(rng());
  packets[5].bytes.clear();  // an empty sample must not be taken for end of stream

  voca::decode::DecoderOptions options;
  options.kind = voca::decode::DecoderKind::kSoftware;
  voca::decode::VideoDecoder decoder(demuxer.stream(), options, nullptr, "good.mp4");
  DecodedFrame frame;
  int decoded = 0;
  const std::string message = inputErrorOf([&] {
    for (const voca::decode::Packet& p : packets) {
      decoder.send(p);
      while (decoder.receive(frame)) ++decoded;
    }
    decoder.sendEnd();
    while (decoder.receive(frame)) ++decoded;
  });
  CHECK(message.find("good.mp4") != std::string::npos);
  CHECK(message.find(" 3") != std::string::npos);  // "packet 3" or "frame 3"
  CHECK(decoded == 3);                             // frames before the damage came out intact
}

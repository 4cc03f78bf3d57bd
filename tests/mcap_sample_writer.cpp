// Writes MCAP files with the McapWriter for tests/test_mcap_reader.py, and beside each a JSON manifest of
// what was passed to the writer (schemas, channels, and every message whose write() returned true), so the
// independent Python reader can check that all of it, and only it, comes back.
//
//   mcap_sample_writer <plan> <out.mcap> <manifest.json> [<copy.mcap>]
//
// Plans: small (a few records of each kind, for cutting at every byte), full (empty and multi-megabyte
// payloads, extreme times and sequences, a schema without encoding, channel metadata, UTF-8 topics,
// schemas and channels added after messages), many (1000 channels), copy (the file copied to <copy.mcap>
// halfway, as a crash would leave it, then closed), killed (SIGKILL after the last write, never closed),
// file-limit (the file size limit stops the writer mid-record, as a full disk would).

#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "drivers/mcap/mcap_writer.h"

namespace {

using Bytes = std::vector<std::uint8_t>;

std::string hex(const Bytes& bytes) {
  std::string text;
  text.reserve(2 * bytes.size());
  for (std::uint8_t b : bytes) text += fmt::format("{:02x}", b);
  return text;
}

Bytes text(std::string_view s) { return Bytes(s.begin(), s.end()); }

// Writes through the McapWriter and records in the manifest what it was given.
class Recorder {
 public:
  Recorder(const std::filesystem::path& file, std::string_view library) : writer_(file, library) {
    manifest_["library"] = library;
    manifest_["schemas"] = nlohmann::json::array();
    manifest_["channels"] = nlohmann::json::array();
    manifest_["messages"] = nlohmann::json::array();
  }

  std::uint16_t schema(const std::string& name, const std::string& encoding, const Bytes& data) {
    const std::uint16_t id = writer_.addSchema(name, encoding, data);
    manifest_["schemas"].push_back({{"id", id}, {"name", name}, {"encoding", encoding}, {"data", hex(data)}});
    return id;
  }

  std::uint16_t channel(std::uint16_t schema_id, const std::string& topic, const std::string& encoding,
                        const std::map<std::string, std::string>& metadata = {}) {
    const std::uint16_t id = writer_.addChannel(schema_id, topic, encoding, metadata);
    manifest_["channels"].push_back({{"id", id},
                                     {"schema_id", schema_id},
                                     {"topic", topic},
                                     {"message_encoding", encoding},
                                     {"metadata", metadata}});
    return id;
  }

  bool message(std::uint16_t channel, std::uint32_t sequence, std::uint64_t log_time, std::uint64_t publish_time,
               const Bytes& data) {
    if (!writer_.write(channel, sequence, log_time, publish_time, data)) return false;
    manifest_["messages"].push_back({{"channel_id", channel},
                                     {"sequence", sequence},
                                     {"log_time", log_time},
                                     {"publish_time", publish_time},
                                     {"data", hex(data)}});
    return true;
  }

  voca::mcap::McapWriter& writer() { return writer_; }
  nlohmann::json& manifest() { return manifest_; }

  void saveManifest(const std::filesystem::path& path) {
    manifest_["closed"] = closed_;
    manifest_["error"] = writer_.error();
    manifest_["bytes_written"] = writer_.bytesWritten();
    std::ofstream out(path);
    out << manifest_.dump(1) << "\n";
    out.close();
    if (!out) throw std::runtime_error("cannot write " + path.string());
  }

  bool close() {
    closed_ = writer_.close();
    return closed_;
  }

 private:
  voca::mcap::McapWriter writer_;
  nlohmann::json manifest_;
  bool closed_ = false;
};

Bytes randomBytes(std::mt19937& random, std::size_t size) {
  Bytes bytes(size);
  for (auto& b : bytes) b = static_cast<std::uint8_t>(random());
  return bytes;
}

const char* kPoseSchema =
    R"({"title":"foxglove.PoseInFrame","type":"object","properties":{"timestamp":{"type":"object"},)"
    R"("frame_id":{"type":"string"},"pose":{"type":"object"}}})";

void small(Recorder& r) {
  const auto pose = r.schema("foxglove.PoseInFrame", "jsonschema", text(kPoseSchema));
  const auto odom = r.channel(pose, "/odom", "json", {{"frame", "world"}});
  const auto raw = r.channel(0, "/raw", "x-raw");
  for (std::uint32_t k = 0; k < 6; ++k) {
    r.message(odom, k, 1'000'000'000ull + 50'000'000ull * k, 1'000'000'000ull + 50'000'000ull * k + 7,
              text(fmt::format(R"({{"k":{}}})", k)));
    r.message(raw, 100 + k, 1'000'000'000ull + 50'000'000ull * k + 1, 5, Bytes(k % 3, static_cast<std::uint8_t>(k)));
  }
  const auto late = r.channel(pose, "/late", "json");
  r.message(late, 0, 900'000'000ull, 900'000'000ull, text("{}"));
}

void full(Recorder& r) {
  std::mt19937 random(20240611);
  const auto pose = r.schema("foxglove.PoseInFrame", "jsonschema", text(kPoseSchema));
  const auto none = r.schema("voca.Opaque", "", {});
  Bytes all_bytes(256);
  for (int b = 0; b < 256; ++b) all_bytes[static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(b);
  const auto blob = r.schema("voca.Blob", "x-voca-blob", all_bytes);
  const auto odom = r.channel(pose, "/voca/pose", "json");
  const auto raw = r.channel(0, "/voca/raw", "x-voca-raw", {{"camera", "left"}, {"rate_hz", "20"}, {"", ""}});
  const auto big = r.channel(blob, "/voca/größe/ünïcode", "x-voca-blob");
  const auto opaque = r.channel(none, "/voca/opaque", "x-voca-raw");
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();
  r.message(odom, 0, 0, 0, text(R"({"pose":1})"));
  r.message(raw, std::numeric_limits<std::uint32_t>::max(), kMax, kMax, {});
  r.message(big, 7, 5'000'000'000ull, 4'999'000'000ull, randomBytes(random, (4u << 20) + 3));
  r.message(opaque, 1, 3, 2, randomBytes(random, 1));
  r.message(raw, 2, 1'000, 2'000, {});
  for (std::uint32_t k = 0; k < 200; ++k) {
    r.message(odom, k + 1, 6'000'000'000ull + 33'333'333ull * k, 6'000'000'000ull + 33'333'333ull * k - 100,
              randomBytes(random, k % 97));
  }
  r.message(big, 8, 5'000'000'001ull, 5'000'000'001ull, randomBytes(random, 1u << 20));
  // Added after messages were written: a reader meets them before their first message all the same.
  const auto late_schema = r.schema("voca.Late", "jsonschema", text(R"({"type":"object"})"));
  const auto late = r.channel(late_schema, "/voca/late", "json", {{"added", "after messages"}});
  r.message(late, 0, 4'000'000'000ull, 4'000'000'000ull, text("{}"));
  r.message(odom, 999, 1, 1, text("{}"));  // log time before the others: statistics take the minimum
}

void many(Recorder& r) {
  std::mt19937 random(7);
  const auto a = r.schema("voca.A", "jsonschema", text("{}"));
  const auto b = r.schema("voca.B", "jsonschema", text(R"({"type":"object"})"));
  std::vector<std::uint16_t> channels;
  for (int c = 0; c < 1000; ++c) {
    channels.push_back(r.channel(c % 3 == 0 ? 0 : (c % 3 == 1 ? a : b), fmt::format("/many/{}", c), "json",
                                 {{"index", std::to_string(c)}}));
  }
  for (std::uint32_t k = 0; k < 3000; ++k) {
    r.message(channels[(k * 7) % channels.size()], k, 10'000ull * k, 10'000ull * k, randomBytes(random, k % 65));
  }
}

// The first half, the file copied as it is (what a crash at that point leaves), the second half, close.
void copy(Recorder& r, const std::filesystem::path& file, const std::filesystem::path& copy_path) {
  std::mt19937 random(11);
  const auto pose = r.schema("foxglove.PoseInFrame", "jsonschema", text(kPoseSchema));
  const auto odom = r.channel(pose, "/odom", "json");
  for (std::uint32_t k = 0; k < 40; ++k) r.message(odom, k, 100ull * k, 100ull * k, randomBytes(random, 10 + k));
  std::filesystem::copy_file(file, copy_path, std::filesystem::copy_options::overwrite_existing);
  r.manifest()["copied_messages"] = r.manifest()["messages"].size();
  const auto late = r.channel(0, "/after_copy", "x-raw");
  for (std::uint32_t k = 40; k < 60; ++k) r.message(late, k, 100ull * k, 100ull * k, randomBytes(random, 3000));
}

void killed(Recorder& r) {
  std::mt19937 random(13);
  const auto pose = r.schema("foxglove.PoseInFrame", "jsonschema", text(kPoseSchema));
  const auto odom = r.channel(pose, "/odom", "json");
  const auto image = r.channel(0, "/image", "x-jpeg");
  for (std::uint32_t k = 0; k < 30; ++k) {
    r.message(odom, k, 1'000'000ull * k, 1'000'000ull * k, randomBytes(random, 40));
    r.message(image, k, 1'000'000ull * k + 1, 1'000'000ull * k + 1, randomBytes(random, 20000 + 977 * k));
  }
}

// Messages of 1000 bytes until the file size limit (as a full disk) fails a write in the middle of one.
void fileLimit(Recorder& r) {
  std::signal(SIGXFSZ, SIG_IGN);  // the write then fails with EFBIG instead of the process being killed
  rlimit limit{};
  limit.rlim_cur = 20'000;
  limit.rlim_max = RLIM_INFINITY;
  if (setrlimit(RLIMIT_FSIZE, &limit) != 0) throw std::runtime_error("setrlimit(RLIMIT_FSIZE) failed");
  std::mt19937 random(17);
  const auto odom = r.channel(0, "/odom", "x-raw");
  int refused = 0;
  for (std::uint32_t k = 0; k < 100; ++k) {
    if (!r.message(odom, k, 10ull * k, 10ull * k, randomBytes(random, 1000))) ++refused;
  }
  r.manifest()["refused_writes"] = refused;
  limit.rlim_cur = RLIM_INFINITY;
  setrlimit(RLIMIT_FSIZE, &limit);  // for the manifest
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: mcap_sample_writer small|full|many|copy|killed|file-limit <out.mcap> <manifest.json> "
                 "[<copy.mcap>]\n";
    return 2;
  }
  const std::string plan = argv[1];
  const std::filesystem::path file = argv[2], manifest = argv[3];
  try {
    Recorder r(file, "voca-rt tests/mcap_sample_writer");
    if (plan == "small") {
      small(r);
    } else if (plan == "full") {
      full(r);
    } else if (plan == "many") {
      many(r);
    } else if (plan == "copy" && argc == 5) {
      copy(r, file, argv[4]);
    } else if (plan == "killed") {
      killed(r);
      r.saveManifest(manifest);
      std::raise(SIGKILL);  // no close(), no destructor: what a crash leaves
    } else if (plan == "file-limit") {
      fileLimit(r);
    } else {
      std::cerr << "unknown plan '" << plan << "'\n";
      return 2;
    }
    r.close();
    r.saveManifest(manifest);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

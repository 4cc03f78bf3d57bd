// The MCAP writer against the specification: a file written byte for byte as the specification lays it
// out (built here by hand), the CRC-32 on known answers, records handed to the OS one by one, and
// failures: an unwritable path is an InputError, a full device or a file size limit stops the writer
// with a message and false from every later call, never an exception. What the files hold is read
// back by the independent reader in tests/test_mcap_reader.py.

#include <doctest/doctest.h>

#include <algorithm>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "drivers/mcap/crc32.h"
#include "drivers/mcap/mcap_writer.h"
#include "tests/test_support.h"
#include "voca/core/error.h"

namespace {

using Bytes = std::vector<std::uint8_t>;
using voca::mcap::McapWriter;

Bytes readAll(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Little-endian fields, for writing the expected bytes by hand.
void u8(Bytes& out, std::uint8_t v) { out.push_back(v); }
void u16(Bytes& out, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void u32(Bytes& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void u64(Bytes& out, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void raw(Bytes& out, std::initializer_list<std::uint8_t> bytes) { out.insert(out.end(), bytes); }

std::uint32_t crcOf(const Bytes& bytes, std::size_t begin, std::size_t end) {
  return voca::mcap::crc32(0, std::span<const std::uint8_t>(bytes.data() + begin, end - begin));
}

}  // namespace

TEST_CASE("crc32: the CRC-32 of zlib and MCAP, in any pieces") {
  const std::string check = "123456789";
  const std::span<const std::uint8_t> check_bytes(reinterpret_cast<const std::uint8_t*>(check.data()), check.size());
  CHECK(voca::mcap::crc32(0, check_bytes) == 0xCBF43926u);  // the catalogue's check value of CRC-32/ISO-HDLC
  CHECK(voca::mcap::crc32(0, {}) == 0u);
  const Bytes zeros(32, 0);
  CHECK(voca::mcap::crc32(0, zeros) == 0x190A55ADu);  // 32 zero bytes (RFC 3720 B.4 lists the same register)

  std::mt19937 random(3);
  Bytes data(1000);
  for (auto& b : data) b = static_cast<std::uint8_t>(random());
  const std::uint32_t whole = voca::mcap::crc32(0, data);
  for (std::size_t split : {0, 1, 7, 8, 9, 500, 999, 1000}) {
    const std::span<const std::uint8_t> all(data);
    CHECK(voca::mcap::crc32(voca::mcap::crc32(0, all.first(split)), all.subspan(split)) == whole);
  }
}

TEST_CASE("writer: a small file byte for byte as the specification lays it out") {
  voca::test::ScratchDir dir("mcap-known");
  const auto path = dir / "known.mcap";
  {
    McapWriter writer(path, "kat");
    CHECK(writer.addSchema("s", "jsonschema", std::string_view("{}")) == 1);
    CHECK(writer.addChannel(1, "/a", "json", {{"k", "v"}}) == 1);
    const Bytes payload = {0xAB, 0xCD};
    CHECK(writer.write(1, 0x01020304u, 0x1122334455667788ull, 0x0102030405060708ull, payload));
    CHECK(writer.close());
    CHECK(writer.ok());
  }
  const Bytes file = readAll(path);

  Bytes expected;
  raw(expected, {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});
  // Header: opcode 0x01, content length 11 = profile "" (4) + library "kat" (4 + 3).
  raw(expected, {0x01, 11, 0, 0, 0, 0, 0, 0, 0});
  raw(expected, {0, 0, 0, 0});
  raw(expected, {3, 0, 0, 0, 'k', 'a', 't'});
  const std::size_t schema_at = expected.size();
  // Schema: id 1, name "s", encoding "jsonschema", data "{}": 2 + 5 + 14 + 6 = 27 bytes.
  raw(expected, {0x03, 27, 0, 0, 0, 0, 0, 0, 0});
  raw(expected, {1, 0});
  raw(expected, {1, 0, 0, 0, 's'});
  raw(expected, {10, 0, 0, 0, 'j', 's', 'o', 'n', 's', 'c', 'h', 'e', 'm', 'a'});
  raw(expected, {2, 0, 0, 0, '{', '}'});
  const std::size_t channel_at = expected.size();
  // Channel: id 1, schema 1, topic "/a", encoding "json", metadata {k: v} (a 10-byte map): 32 bytes.
  raw(expected, {0x04, 32, 0, 0, 0, 0, 0, 0, 0});
  raw(expected, {1, 0, 1, 0});
  raw(expected, {2, 0, 0, 0, '/', 'a'});
  raw(expected, {4, 0, 0, 0, 'j', 's', 'o', 'n'});
  raw(expected, {10, 0, 0, 0, 1, 0, 0, 0, 'k', 1, 0, 0, 0, 'v'});
  const std::size_t records_end = expected.size();
  // Message: channel 1, sequence, log time, publish time, then the payload to the record's end: 24 bytes.
  raw(expected, {0x05, 24, 0, 0, 0, 0, 0, 0, 0});
  raw(expected, {1, 0});
  raw(expected, {0x04, 0x03, 0x02, 0x01});
  raw(expected, {0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11});
  raw(expected, {0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01});
  raw(expected, {0xAB, 0xCD});
  // Data End: the CRC-32 of every byte before it.
  const std::size_t data_end_at = expected.size();
  raw(expected, {0x0F, 4, 0, 0, 0, 0, 0, 0, 0});
  u32(expected, crcOf(expected, 0, data_end_at));
  // Summary: the Schema and Channel records again, then Statistics.
  const std::size_t summary_at = expected.size();
  expected.insert(expected.end(), expected.begin() + static_cast<std::ptrdiff_t>(schema_at),
                  expected.begin() + static_cast<std::ptrdiff_t>(records_end));
  const std::size_t statistics_at = expected.size();
  u8(expected, 0x0B);
  u64(expected, 8 + 2 + 4 + 4 + 4 + 4 + 8 + 8 + 4 + 10);
  u64(expected, 1);                      // messages
  u16(expected, 1);                      // schemas
  u32(expected, 1);                      // channels
  u32(expected, 0);                      // attachments
  u32(expected, 0);                      // metadata
  u32(expected, 0);                      // chunks
  u64(expected, 0x1122334455667788ull);  // first log time
  u64(expected, 0x1122334455667788ull);  // last log time
  u32(expected, 10);                     // the per-channel map: channel 1 -> 1 message
  u16(expected, 1);
  u64(expected, 1);
  const std::size_t summary_offsets_at = expected.size();
  // One Summary Offset per group: opcode, start, length.
  const std::pair<std::uint8_t, std::pair<std::size_t, std::size_t>> groups[] = {
      {0x03, {summary_at, channel_at - schema_at}},
      {0x04, {summary_at + channel_at - schema_at, records_end - channel_at}},
      {0x0B, {statistics_at, summary_offsets_at - statistics_at}}};
  for (const auto& [opcode, where] : groups) {
    u8(expected, 0x0E);
    u64(expected, 17);
    u8(expected, opcode);
    u64(expected, where.first);
    u64(expected, where.second);
  }
  // Footer: summary start, summary offset start, CRC-32 from the summary through those two fields.
  u8(expected, 0x02);
  u64(expected, 20);
  u64(expected, summary_at);
  u64(expected, summary_offsets_at);
  u32(expected, crcOf(expected, summary_at, expected.size()));
  raw(expected, {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'});

  REQUIRE(file.size() == expected.size());
  for (std::size_t i = 0; i < file.size(); ++i) {
    INFO("byte " << i);
    REQUIRE(int(file[i]) == int(expected[i]));
  }
}

TEST_CASE("writer: a file without schemas, channels or messages still has its summary") {
  voca::test::ScratchDir dir("mcap-empty");
  McapWriter writer(dir / "empty.mcap", "");
  CHECK(writer.close());
  const Bytes file = readAll(dir / "empty.mcap");
  CHECK(file.size() == writer.bytesWritten());
  // magic 8, Header 9 + 8, Data End 9 + 4, Statistics 9 + 46, one Summary Offset 9 + 17, Footer 9 + 20, magic 8.
  CHECK(file.size() == 8 + 17 + 13 + 55 + 26 + 29 + 8);
  // Statistics: no messages, so both times are zero, and the per-channel map is empty.
  const std::size_t statistics = 8 + 17 + 13;
  CHECK(file[statistics] == 0x0B);
  CHECK(std::all_of(file.begin() + statistics + 9, file.begin() + statistics + 55,
                    [](std::uint8_t b) { return b == 0; }));
}

TEST_CASE("writer: every record is in the file when its call returns, before close") {
  voca::test::ScratchDir dir("mcap-handed");
  const auto path = dir / "live.mcap";
  McapWriter writer(path, "live");
  CHECK(std::filesystem::file_size(path) == 8 + 9 + 4 + (4 + 4));  // magic, Header ("", "live")
  const auto schema = writer.addSchema("s", "jsonschema", std::string_view("{}"));
  const auto channel = writer.addChannel(schema, "/t", "json");
  CHECK(std::filesystem::file_size(path) == writer.bytesWritten());
  std::mt19937 random(5);
  Bytes payload;
  for (std::uint32_t k = 0; k < 50; ++k) {
    payload.assign(random() % 5000, static_cast<std::uint8_t>(k));
    const std::uint64_t before = writer.bytesWritten();
    REQUIRE(writer.write(channel, k, k, k, payload));
    CHECK(writer.bytesWritten() == before + 31 + payload.size());
    // What another process (or a copy after a crash) sees: the file has the whole record already.
    REQUIRE(std::filesystem::file_size(path) == writer.bytesWritten());
    const Bytes file = readAll(path);
    CHECK(file[before] == 0x05);
    CHECK(std::equal(payload.begin(), payload.end(), file.end() - static_cast<std::ptrdiff_t>(payload.size())));
  }
  CHECK(writer.messageCount() == 50);
  CHECK(writer.close());
}

TEST_CASE("writer: an unwritable path is an InputError naming the file") {
  voca::test::ScratchDir dir("mcap-paths");
  const auto missing = dir / "no-such-folder" / "out.mcap";
  const std::string error = voca::test::inputErrorOf([&] { McapWriter writer(missing, "x"); });
  voca::test::expectError(error, missing.string());
  voca::test::expectError(error, "does not exist");
  CHECK_FALSE(std::filesystem::exists(missing));

  const std::string folder_error = voca::test::inputErrorOf([&] { McapWriter writer(dir.path(), "x"); });
  voca::test::expectError(folder_error, dir.path().string());
  voca::test::expectError(folder_error, "Is a directory");
}

TEST_CASE("writer: /dev/full stops the writer with a message, false from every call, no exception") {
  if (!std::filesystem::exists("/dev/full")) return;
  std::optional<McapWriter> writer;
  REQUIRE_NOTHROW(writer.emplace("/dev/full", "full"));
  CHECK_FALSE(writer->ok());
  voca::test::expectError(writer->error(), "/dev/full");
  voca::test::expectError(writer->error(), "No space left on device");
  const std::string first_error = writer->error();
  std::uint16_t channel = 0;
  CHECK_NOTHROW(channel =
                    writer->addChannel(writer->addSchema("s", "jsonschema", std::string_view("{}")), "/t", "json"));
  CHECK(channel == 1);
  const Bytes payload(100, 1);
  for (int k = 0; k < 3; ++k) {
    bool written = true;
    CHECK_NOTHROW(written = writer->write(channel, 0, 0, 0, payload));
    CHECK_FALSE(written);
  }
  bool closed = true;
  CHECK_NOTHROW(closed = writer->close());
  CHECK_FALSE(closed);
  CHECK(writer->error() == first_error);  // the first failure is the one reported
  CHECK(writer->messageCount() == 0);
}

TEST_CASE("writer: a write failing mid-run keeps every record before it and refuses the rest") {
  voca::test::ScratchDir dir("mcap-limit");
  const auto path = dir / "limited.mcap";
  // RLIMIT_FSIZE fails a write past the limit with EFBIG (with SIGXFSZ ignored), as a full disk would.
  const auto previous_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit previous{};
  REQUIRE(getrlimit(RLIMIT_FSIZE, &previous) == 0);
  rlimit limit = previous;
  limit.rlim_cur = 10'000;
  REQUIRE(setrlimit(RLIMIT_FSIZE, &limit) == 0);
  McapWriter writer(path, "limited");
  const auto channel = writer.addChannel(0, "/t", "x");
  const Bytes payload(900, 7);
  int written = 0, refused = 0;
  for (int k = 0; k < 20; ++k) {
    bool ok = false;
    CHECK_NOTHROW(ok = writer.write(channel, 0, 0, 0, payload));
    (ok ? written : refused) += 1;
  }
  setrlimit(RLIMIT_FSIZE, &previous);
  std::signal(SIGXFSZ, previous_handler);
  // The header and channel take 60 bytes, each message 931: ten fit under 10000, the eleventh is cut.
  CHECK(written == 10);
  CHECK(refused == 10);
  CHECK(writer.messageCount() == 10);
  voca::test::expectError(writer.error(), path.string());
  voca::test::expectError(writer.error(), "File too large");
  CHECK_FALSE(writer.close());
  CHECK(std::filesystem::file_size(path) == 10'000);
  CHECK(writer.bytesWritten() == 10'000);
}

TEST_CASE("writer: ids it did not hand out and calls after close are caller errors") {
  voca::test::ScratchDir dir("mcap-misuse");
  McapWriter writer(dir / "misuse.mcap", "misuse");
  CHECK_THROWS_AS(writer.addChannel(1, "/t", "json"), std::invalid_argument);  // no schema 1 yet
  const auto channel = writer.addChannel(0, "/t", "json");
  const Bytes payload(3, 0);
  CHECK_THROWS_AS(writer.write(0, 0, 0, 0, payload), std::invalid_argument);
  CHECK_THROWS_AS(writer.write(static_cast<std::uint16_t>(channel + 1), 0, 0, 0, payload), std::invalid_argument);
  CHECK(writer.write(channel, 0, 0, 0, payload));
  CHECK(writer.close());
  CHECK(writer.close());  // the first answer again
  CHECK_THROWS_AS(writer.write(channel, 0, 0, 0, payload), std::logic_error);
  CHECK_THROWS_AS(writer.addSchema("s", "", std::string_view()), std::logic_error);
}

TEST_CASE("writer: 65535 channels, and the 65536th is refused") {
  voca::test::ScratchDir dir("mcap-ids");
  McapWriter writer(dir / "ids.mcap", "ids");
  std::uint16_t last = 0;
  for (int c = 0; c < 65535; ++c) last = writer.addChannel(0, "/c", "x");
  CHECK(last == 65535);
  CHECK_THROWS_AS(writer.addChannel(0, "/c", "x"), std::length_error);
  const Bytes payload(1, 0);
  CHECK(writer.write(65535, 0, 0, 0, payload));
  CHECK(writer.close());
}

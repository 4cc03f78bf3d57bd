#include "drivers/mcap/mcap_writer.h"

#include <fmt/core.h>

#include <algorithm>
#include <cerrno>
#include <exception>
#include <limits>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <sys/uio.h>
#include <unistd.h>

#include "drivers/mcap/crc32.h"
#include "voca/core/error.h"

namespace voca::mcap {

namespace {

// Record opcodes of the specification.
enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Opcode (1 byte) and content length (uint64) before every record's content.
constexpr std::size_t kRecordPrefixBytes = 9;
// A Message's fixed fields: channel id, sequence, log time, publish time.
constexpr std::size_t kMessageFixedBytes = 2 + 4 + 8 + 8;
// summary_start, summary_offset_start, summary_crc: the Footer is never extended.
constexpr std::size_t kFooterContentBytes = 8 + 8 + 4;
constexpr std::size_t kMaxIds = std::numeric_limits<std::uint16_t>::max();

// Integers are little-endian whatever the host.
void storeLittleEndian(std::uint8_t* out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}

void append(std::vector<std::uint8_t>& out, std::uint64_t value, int bytes) {
  const std::size_t at = out.size();
  out.resize(at + static_cast<std::size_t>(bytes));
  storeLittleEndian(out.data() + at, value, bytes);
}

void appendBytes(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> bytes) {
  out.insert(out.end(), bytes.begin(), bytes.end());
}

std::span<const std::uint8_t> asBytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

// A uint32 length prefix: strings, schema data and maps cannot exceed 4 GiB.
std::uint32_t length32(std::size_t size, std::string_view what) {
  if (size > std::numeric_limits<std::uint32_t>::max()) {
    throw std::length_error(fmt::format("MCAP {} of {} bytes: the format's limit is 4 GiB", what, size));
  }
  return static_cast<std::uint32_t>(size);
}

// String and uint32-prefixed Bytes share one encoding: the byte length, then the bytes.
void appendPrefixed(std::vector<std::uint8_t>& out, std::span<const std::uint8_t> bytes, std::string_view what) {
  append(out, length32(bytes.size(), what), 4);
  appendBytes(out, bytes);
}

// Starts a record whose content length is filled in by finishRecord.
std::size_t beginRecord(std::vector<std::uint8_t>& out, Opcode opcode) {
  const std::size_t start = out.size();
  out.push_back(opcode);
  append(out, 0, 8);
  return start;
}

void finishRecord(std::vector<std::uint8_t>& out, std::size_t start) {
  storeLittleEndian(out.data() + start + 1, out.size() - start - kRecordPrefixBytes, 8);
}

std::string osMessage(int os_error) { return std::generic_category().message(os_error); }

}  // namespace

McapWriter::McapWriter(const std::filesystem::path& file, std::string_view library) : path_(file) {
  std::vector<std::uint8_t> start(kMagic.begin(), kMagic.end());
  const std::size_t header = beginRecord(start, kHeader);
  appendPrefixed(start, {}, "profile");
  appendPrefixed(start, asBytes(library), "library name");
  finishRecord(start, header);
  storeLittleEndian(message_head_.data(), kMessage, 1);

  fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    const int os_error = errno;
    if (os_error == ENOENT) {
      const std::filesystem::path folder = file.has_parent_path() ? file.parent_path() : ".";
      throw InputError(
          fmt::format("{}: cannot create the MCAP file: its folder {} does not exist", file.string(), folder.string()));
    }
    throw InputError(fmt::format("{}: cannot create the MCAP file: {}", file.string(), osMessage(os_error)));
  }
  writeRecord(start, {});
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (const std::exception&) {
    // Out of memory for the summary: a destructor cannot report it; the data section is on disk.
  }
  closeFile();
}

void McapWriter::requireOpen(const char* call) const {
  if (closed_) throw std::logic_error(fmt::format("{}: McapWriter::{} after close()", path_.string(), call));
}

std::uint16_t McapWriter::addSchema(std::string_view name, std::string_view encoding, std::string_view data) {
  return addSchema(name, encoding, asBytes(data));
}

std::uint16_t McapWriter::addSchema(std::string_view name, std::string_view encoding,
                                    std::span<const std::uint8_t> data) {
  requireOpen("addSchema");
  if (schema_records_.size() >= kMaxIds) {
    throw std::length_error(fmt::format("{}: more than {} MCAP schemas", path_.string(), kMaxIds));
  }
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);
  std::vector<std::uint8_t> record;
  record.reserve(kRecordPrefixBytes + 2 + 12 + name.size() + encoding.size() + data.size());
  const std::size_t start = beginRecord(record, kSchema);
  append(record, id, 2);
  appendPrefixed(record, asBytes(name), "schema name");
  appendPrefixed(record, asBytes(encoding), "schema encoding");
  appendPrefixed(record, data, "schema");
  finishRecord(record, start);
  if (ok()) writeRecord(record, {});
  schema_records_.push_back(std::move(record));
  return id;
}

std::uint16_t McapWriter::addChannel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                     const std::map<std::string, std::string>& metadata) {
  requireOpen("addChannel");
  if (schema_id > schema_records_.size()) {
    throw std::invalid_argument(fmt::format("{}: channel '{}' names schema {}, but only {} schemas were added",
                                            path_.string(), topic, schema_id, schema_records_.size()));
  }
  if (channel_records_.size() >= kMaxIds) {
    throw std::length_error(fmt::format("{}: more than {} MCAP channels", path_.string(), kMaxIds));
  }
  const auto id = static_cast<std::uint16_t>(channel_records_.size() + 1);
  std::size_t metadata_bytes = 0;
  for (const auto& [key, value] : metadata) metadata_bytes += 8 + key.size() + value.size();
  std::vector<std::uint8_t> record;
  record.reserve(kRecordPrefixBytes + 4 + 12 + topic.size() + message_encoding.size() + metadata_bytes);
  const std::size_t start = beginRecord(record, kChannel);
  append(record, id, 2);
  append(record, schema_id, 2);
  appendPrefixed(record, asBytes(topic), "topic");
  appendPrefixed(record, asBytes(message_encoding), "message encoding");
  append(record, length32(metadata_bytes, "channel metadata"), 4);
  for (const auto& [key, value] : metadata) {
    appendPrefixed(record, asBytes(key), "metadata key");
    appendPrefixed(record, asBytes(value), "metadata value");
  }
  finishRecord(record, start);
  if (ok()) writeRecord(record, {});
  channel_records_.push_back(std::move(record));
  channel_message_counts_.push_back(0);
  return id;
}

bool McapWriter::write(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time_ns,
                       std::uint64_t publish_time_ns, std::span<const std::uint8_t> data) {
  requireOpen("write");
  if (!ok()) return false;
  if (channel_id == 0 || channel_id > channel_records_.size()) {
    throw std::invalid_argument(
        fmt::format("{}: message on channel {}, which addChannel did not return", path_.string(), channel_id));
  }
  std::uint8_t* head = message_head_.data();
  storeLittleEndian(head + 1, kMessageFixedBytes + data.size(), 8);
  storeLittleEndian(head + 9, channel_id, 2);
  storeLittleEndian(head + 11, sequence, 4);
  storeLittleEndian(head + 15, log_time_ns, 8);
  storeLittleEndian(head + 23, publish_time_ns, 8);
  if (!writeRecord(message_head_, data)) return false;
  if (message_count_ == 0 || log_time_ns < message_start_time_ns_) message_start_time_ns_ = log_time_ns;
  if (message_count_ == 0 || log_time_ns > message_end_time_ns_) message_end_time_ns_ = log_time_ns;
  ++message_count_;
  ++channel_message_counts_[channel_id - 1];
  return true;
}

bool McapWriter::close() {
  if (closed_) return close_result_;
  closed_ = true;
  if (!ok()) return false;

  std::size_t summary_bytes = 256 + 20 * channel_records_.size();
  for (const auto& record : schema_records_) summary_bytes += record.size();
  for (const auto& record : channel_records_) summary_bytes += record.size();
  std::vector<std::uint8_t> tail;
  tail.reserve(summary_bytes);
  const auto offsetOf = [&](std::size_t tail_position) { return bytes_written_ + tail_position; };

  const std::size_t data_end = beginRecord(tail, kDataEnd);
  append(tail, data_crc_, 4);
  finishRecord(tail, data_end);

  // The summary groups records by opcode; each group gets a Summary Offset record.
  struct Group {
    Opcode opcode;
    std::uint64_t start;
    std::uint64_t length;
  };
  std::vector<Group> groups;
  const std::size_t summary_start = tail.size();
  const auto appendGroup = [&](Opcode opcode, const std::vector<std::vector<std::uint8_t>>& records) {
    if (records.empty()) return;
    const std::size_t start = tail.size();
    for (const auto& record : records) appendBytes(tail, record);
    groups.push_back({opcode, offsetOf(start), tail.size() - start});
  };
  appendGroup(kSchema, schema_records_);
  appendGroup(kChannel, channel_records_);

  const std::size_t statistics = beginRecord(tail, kStatistics);
  append(tail, message_count_, 8);
  append(tail, schema_records_.size(), 2);
  append(tail, channel_records_.size(), 4);
  append(tail, 0, 4);  // attachments
  append(tail, 0, 4);  // metadata records
  append(tail, 0, 4);  // chunks
  append(tail, message_start_time_ns_, 8);
  append(tail, message_end_time_ns_, 8);
  append(tail, 10 * channel_message_counts_.size(), 4);
  for (std::size_t c = 0; c < channel_message_counts_.size(); ++c) {
    append(tail, c + 1, 2);
    append(tail, channel_message_counts_[c], 8);
  }
  finishRecord(tail, statistics);
  groups.push_back({kStatistics, offsetOf(statistics), tail.size() - statistics});

  const std::size_t summary_offsets = tail.size();
  for (const Group& group : groups) {
    const std::size_t record = beginRecord(tail, kSummaryOffset);
    append(tail, group.opcode, 1);
    append(tail, group.start, 8);
    append(tail, group.length, 8);
    finishRecord(tail, record);
  }

  // The footer's CRC covers the summary through the footer's own summary_offset_start field, so its
  // opcode and length are in place before it is computed.
  tail.push_back(kFooter);
  append(tail, kFooterContentBytes, 8);
  append(tail, offsetOf(summary_start), 8);
  append(tail, offsetOf(summary_offsets), 8);
  const std::span<const std::uint8_t> summary_crc_range(tail.data() + summary_start, tail.size() - summary_start);
  append(tail, crc32(0, summary_crc_range), 4);
  appendBytes(tail, kMagic);

  close_result_ = writeRecord(tail, {});
  if (fd_ >= 0 && ::close(fd_) != 0) {
    fd_ = -1;
    failWith(errno);
    close_result_ = false;
  }
  fd_ = -1;
  return close_result_;
}

bool McapWriter::writeRecord(std::span<const std::uint8_t> head, std::span<const std::uint8_t> body) {
  if (fd_ < 0) return false;
  data_crc_ = crc32(crc32(data_crc_, head), body);
  std::array<iovec, 2> parts{
      {{const_cast<std::uint8_t*>(head.data()), head.size()}, {const_cast<std::uint8_t*>(body.data()), body.size()}}};
  std::size_t first = 0;
  while (first < parts.size()) {
    if (parts[first].iov_len == 0) {
      ++first;
      continue;
    }
    const ssize_t written = ::writev(fd_, parts.data() + first, static_cast<int>(parts.size() - first));
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) {
      failWith(written < 0 ? errno : EIO);
      return false;
    }
    bytes_written_ += static_cast<std::uint64_t>(written);
    auto left = static_cast<std::size_t>(written);
    while (left > 0) {
      const std::size_t step = std::min(left, parts[first].iov_len);
      parts[first].iov_base = static_cast<std::uint8_t*>(parts[first].iov_base) + step;
      parts[first].iov_len -= step;
      left -= step;
      if (parts[first].iov_len == 0) ++first;
    }
  }
  return true;
}

void McapWriter::failWith(int os_error) {
  error_ = fmt::format("{}: cannot write ({} bytes written): {}", path_.string(), bytes_written_, osMessage(os_error));
  closeFile();
}

void McapWriter::closeFile() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

}  // namespace voca::mcap

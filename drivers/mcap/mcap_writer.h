#pragma once
// An MCAP file writer (the foxglove/mcap format, major version '0'): schemas, channels and
// timestamped messages in one file that Foxglove, Lichtblick, ROS 2 bag tools and the mcap CLI read.
//
// What a file written here guarantees:
// - Unchunked: Schema, Channel and Message records go straight into the data section as they come,
//   with no Chunk, compression or message index, so every complete record can be read in order
//   from the first byte on, also from a file that was never closed.
// - Each record is handed to the operating system (writev(2)) before the call that makes it
//   returns. A crash of the process (abort, SIGKILL, a fault in another thread) therefore loses at
//   most the record being written, which a reader sees as a cut last record. Nothing is fsync'd: a
//   power loss or a kernel crash can lose what the OS had not yet put on the disk.
// - close() (and the destructor) writes Data End (with the CRC-32 of the data section), a summary
//   section (the Schema and Channel records again, then one Statistics record: message count,
//   per-channel counts, first and last log time), a Summary Offset record per group, the Footer
//   (with the CRC-32 of the summary) and the closing magic. Readers that start from the footer
//   need these; a file without them is what a crash leaves and needs a reader that recovers.
// - A failure while writing (disk full, I/O error) stops the writer: it keeps one message naming
//   the file and the OS error (error()), writes nothing more, and every later write(), close()
//   returns false without throwing, so the caller reports it once and its run goes on. The file
//   keeps every record written before the failure.
// - write() allocates nothing: the record's fixed fields are built in a member array and handed
//   to the OS with the payload in one writev(2), without copying the payload.
//
// Not thread-safe: one owner calls it (a sink on one thread).

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace voca::mcap {

// The eight bytes an MCAP file starts and ends with: 0x89 "MCAP" '0' "\r\n".
inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

class McapWriter {
 public:
  // Creates (or truncates) `file` and writes the magic and the Header record (no profile; `library`
  // names the writer, e.g. "voca-rt 1.2"). Throws voca::InputError naming the file and the reason
  // when it cannot be created (missing folder, no permission, a folder). A failure writing the
  // header itself is kept as error(), like any later one.
  McapWriter(const std::filesystem::path& file, std::string_view library);
  // Closes the file as close() does; errors stay unreported (call close() to see them).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // Writes a Schema record and returns its id (1, 2, ...). `encoding` is the schema encoding
  // ("jsonschema", "protobuf", "ros2msg", or "" for none). Throws std::length_error past 65535
  // schemas or for a string or data over 4 GiB, std::logic_error after close(). On a failed
  // writer it only assigns the id.
  std::uint16_t addSchema(std::string_view name, std::string_view encoding, std::span<const std::uint8_t> data);
  std::uint16_t addSchema(std::string_view name, std::string_view encoding, std::string_view data);

  // Writes a Channel record and returns its id (1, 2, ...). `schema_id` is one addSchema returned,
  // or 0 for a channel without a schema; `message_encoding` e.g. "json", "protobuf", "cdr". May be
  // called after messages were written. Throws std::invalid_argument for an unknown schema id,
  // std::length_error past 65535 channels or for a string over 4 GiB, std::logic_error after
  // close(). On a failed writer it only assigns the id.
  std::uint16_t addChannel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                           const std::map<std::string, std::string>& metadata = {});

  // Writes one Message record on `channel_id` and hands it to the OS. Times are nanoseconds in the
  // caller's epoch; `sequence` is the publisher's counter. Returns false, writing nothing, once the
  // writer has failed (and when this write fails). Throws std::invalid_argument for a channel id
  // addChannel did not return, std::logic_error after close().
  bool write(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
             std::span<const std::uint8_t> data);

  // Writes Data End, the summary, the summary offsets, the footer and the magic, then closes the
  // file. True when all of it reached the OS; false on a failed writer (the file then ends at its
  // last complete record, or inside the one being written). A second call returns the first
  // call's answer.
  bool close();

  bool ok() const { return error_.empty(); }
  // "<file>: cannot write (<N> bytes written): <OS error>", empty while nothing failed.
  const std::string& error() const { return error_; }
  const std::filesystem::path& path() const { return path_; }
  // Bytes handed to the OS so far, the file's size when nothing failed.
  std::uint64_t bytesWritten() const { return bytes_written_; }
  std::uint64_t messageCount() const { return message_count_; }

 private:
  // Hands head then body to the OS (writev, looping over short writes and EINTR). On failure keeps
  // the error and closes the file. Feeds the data section's CRC.
  bool writeRecord(std::span<const std::uint8_t> head, std::span<const std::uint8_t> body);
  void failWith(int os_error);
  void closeFile();
  void requireOpen(const char* call) const;

  std::filesystem::path path_;
  int fd_ = -1;
  bool closed_ = false;
  bool close_result_ = false;
  std::string error_;
  std::uint64_t bytes_written_ = 0;
  std::uint32_t data_crc_ = 0;  // CRC-32 of every byte written so far (crc32.h), stored in Data End

  // Complete records (opcode, length, content) kept to repeat in the summary.
  std::vector<std::vector<std::uint8_t>> schema_records_;
  std::vector<std::vector<std::uint8_t>> channel_records_;
  std::vector<std::uint64_t> channel_message_counts_;  // [channel id - 1]
  std::uint64_t message_count_ = 0;
  std::uint64_t message_start_time_ns_ = 0;
  std::uint64_t message_end_time_ns_ = 0;

  // Opcode, length and the fixed fields of a Message record: built here for each write().
  std::array<std::uint8_t, 31> message_head_{};
};

}  // namespace voca::mcap

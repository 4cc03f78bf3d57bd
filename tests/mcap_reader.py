#!/usr/bin/env python3
"""An MCAP reader written from the specification (foxglove/mcap, major version '0'), in plain Python 3,
so tests can check what our writer produces without trusting any code it shares.

It checks the leading and trailing magic, walks every record from the first byte to the last,
checks that every field lies inside its record and every record inside the file, that schemas come
before the channels naming them and channels before their messages, that repeated ids repeat the
same record, the CRCs (Data End, Footer, Chunk, Attachment) where the writer stored them, the
summary section against the data section (Schema and Channel copies, Statistics counts and times,
Summary Offset groups, the Footer's offsets). Uncompressed chunks are read; compressed ones are
refused (the standard library has no zstd or lz4).

As a module:
    import mcap_reader
    f = mcap_reader.read_file("run.mcap")                 # a closed file, checked whole
    f = mcap_reader.read_file("cut.mcap", recover=True)   # every complete record of a cut file
    f.channels[m.channel_id].topic for m in f.messages; f.statistics; f.closed; f.cut_at
As a command:
    python3 tests/mcap_reader.py file.mcap [--recover] [--list]
prints the schemas, channels, messages per topic and the time range; exit code 1 and the offset of
the first malformed record on bad input.
"""

import argparse
import dataclasses
import struct
import sys
import zlib

MAGIC = b"\x89MCAP0\r\n"

HEADER = 0x01
FOOTER = 0x02
SCHEMA = 0x03
CHANNEL = 0x04
MESSAGE = 0x05
CHUNK = 0x06
MESSAGE_INDEX = 0x07
CHUNK_INDEX = 0x08
ATTACHMENT = 0x09
ATTACHMENT_INDEX = 0x0A
STATISTICS = 0x0B
METADATA = 0x0C
METADATA_INDEX = 0x0D
SUMMARY_OFFSET = 0x0E
DATA_END = 0x0F

NAMES = {HEADER: "Header", FOOTER: "Footer", SCHEMA: "Schema", CHANNEL: "Channel", MESSAGE: "Message",
         CHUNK: "Chunk", MESSAGE_INDEX: "Message Index", CHUNK_INDEX: "Chunk Index", ATTACHMENT: "Attachment",
         ATTACHMENT_INDEX: "Attachment Index", STATISTICS: "Statistics", METADATA: "Metadata",
         METADATA_INDEX: "Metadata Index", SUMMARY_OFFSET: "Summary Offset", DATA_END: "Data End"}

DATA_SECTION = {SCHEMA, CHANNEL, MESSAGE, ATTACHMENT, CHUNK, MESSAGE_INDEX, METADATA}
SUMMARY_SECTION = {SCHEMA, CHANNEL, CHUNK_INDEX, ATTACHMENT_INDEX, STATISTICS, METADATA_INDEX}
PREFIX = 9  # opcode (uint8) and content length (uint64) before every record's content
FOOTER_CONTENT = 20  # summary_start, summary_offset_start (uint64), summary_crc (uint32)


class McapError(Exception):
    """A malformed file: the byte offset where the problem is, and what is wrong there."""

    def __init__(self, offset, message):
        super().__init__(f"offset {offset}: {message}")
        self.offset = offset


@dataclasses.dataclass
class Header:
    profile: str
    library: str


@dataclasses.dataclass
class Schema:
    id: int
    name: str
    encoding: str
    data: bytes


@dataclasses.dataclass
class Channel:
    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict


@dataclasses.dataclass
class Message:
    channel_id: int
    sequence: int
    log_time: int
    publish_time: int
    data: bytes
    offset: int  # of the Message record in the file (inside its chunk for a chunked one)


@dataclasses.dataclass
class Statistics:
    message_count: int
    schema_count: int
    channel_count: int
    attachment_count: int
    metadata_count: int
    chunk_count: int
    message_start_time: int
    message_end_time: int
    channel_message_counts: dict


@dataclasses.dataclass
class SummaryOffset:
    group_opcode: int
    group_start: int
    group_length: int


@dataclasses.dataclass
class Footer:
    summary_start: int
    summary_offset_start: int
    summary_crc: int


@dataclasses.dataclass
class Record:
    opcode: int
    offset: int  # of the opcode byte
    length: int  # of the content, without the 9-byte prefix


@dataclasses.dataclass
class McapFile:
    size: int = 0
    header: Header = None
    schemas: dict = dataclasses.field(default_factory=dict)  # id -> Schema, from the data section
    channels: dict = dataclasses.field(default_factory=dict)  # id -> Channel, from the data section
    messages: list = dataclasses.field(default_factory=list)  # in file order
    attachment_count: int = 0
    metadata_count: int = 0
    chunk_count: int = 0
    data_end_crc: int = None  # None: no Data End record was read
    summary_schemas: dict = dataclasses.field(default_factory=dict)
    summary_channels: dict = dataclasses.field(default_factory=dict)
    statistics: Statistics = None
    summary_offsets: list = dataclasses.field(default_factory=list)
    footer: Footer = None
    records: list = dataclasses.field(default_factory=list)  # every top-level record, in order
    ignored: list = dataclasses.field(default_factory=list)  # what the specification says to skip, and why
    cut_at: int = None  # recover mode: where the last, incomplete record starts (None: nothing was cut)

    @property
    def closed(self):
        """True when the file ends with a footer and the magic (what a writer's close() leaves)."""
        return self.footer is not None and self.cut_at is None


class Fields:
    """Reads the fields of one record's content, each checked against the record's end."""

    def __init__(self, buffer, start, end, record_offset, record_name):
        self.buffer = buffer
        self.position = start
        self.end = end
        self.record_offset = record_offset
        self.record_name = record_name

    def _take(self, size, field):
        if size > self.end - self.position:
            raise McapError(self.record_offset,
                            f"{self.record_name} record: {field} needs {size} bytes at record offset "
                            f"{self.position - self.record_offset}, but the record has {self.end - self.position} "
                            f"left")
        start = self.position
        self.position += size
        return start

    def _int(self, format_code, size, field):
        return struct.unpack_from(format_code, self.buffer, self._take(size, field))[0]

    def u8(self, field):
        return self._int("<B", 1, field)

    def u16(self, field):
        return self._int("<H", 2, field)

    def u32(self, field):
        return self._int("<I", 4, field)

    def u64(self, field):
        return self._int("<Q", 8, field)

    def raw(self, size, field):
        start = self._take(size, field)
        return bytes(self.buffer[start:start + size])

    def bytes32(self, field):
        return self.raw(self.u32(field + " length"), field)

    def bytes64(self, field):
        return self.raw(self.u64(field + " length"), field)

    def string(self, field):
        at = self.position
        data = self.bytes32(field)
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise McapError(self.record_offset, f"{self.record_name} record: {field} at record offset "
                                                f"{at - self.record_offset} is not UTF-8 ({e.reason})") from None

    def rest(self):
        return self.raw(self.end - self.position, "data")

    def sub(self, size, field):
        """The next `size` bytes as their own Fields (a map's or an array's entries)."""
        start = self._take(size, field)
        return Fields(self.buffer, start, start + size, self.record_offset, f"{self.record_name} record's {field}")

    def done(self):
        return self.position == self.end

    def string_map(self, field):
        entries = self.sub(self.u32(field + " length"), field)
        result = {}
        while not entries.done():
            key = entries.string("key")
            if key in result:
                raise McapError(self.record_offset, f"{self.record_name} record: {field} repeats the key '{key}'")
            result[key] = entries.string(f"value of '{key}'")
        return result

    def u16_u64_map(self, field):
        entries = self.sub(self.u32(field + " length"), field)
        result = {}
        while not entries.done():
            key = entries.u16("key")
            if key in result:
                raise McapError(self.record_offset, f"{self.record_name} record: {field} repeats the key {key}")
            result[key] = entries.u64(f"value of {key}")
        return result

    def u64_pairs(self, field):
        entries = self.sub(self.u32(field + " length"), field)
        result = []
        while not entries.done():
            result.append((entries.u64("time"), entries.u64("offset")))
        return result


class _Reader:
    def __init__(self, buffer, recover):
        self.buffer = buffer
        self.recover = recover
        self.file = McapFile(size=len(buffer))
        self.section = "start"  # start, data, summary, summary offsets, end
        self.data_end_offset = None
        self.summary_groups = []  # [opcode, start, length] in order
        self.first_summary_offset = None
        self.seen_opcodes_in_summary = set()
        self.schema_records = {}  # id -> (raw content, offset) of the data section's first record with it
        self.channel_records = {}

    # --- the walk -----------------------------------------------------------------------------

    def read(self):
        buffer = self.buffer
        if len(buffer) < len(MAGIC) and self.recover and MAGIC.startswith(bytes(buffer)):
            self.file.cut_at = 0
            return self.file
        if bytes(buffer[:len(MAGIC)]) != MAGIC:
            raise McapError(0, f"not an MCAP file: starts with {bytes(buffer[:8]).hex(' ')}, expected "
                               f"{MAGIC.hex(' ')}")
        position = len(MAGIC)
        while self.section != "end":
            if position == len(buffer):
                if self.recover:
                    return self._finish_cut(position)
                raise McapError(position, f"the file ends after {len(buffer)} bytes without a Footer record and "
                                          f"the closing magic (not closed by its writer? --recover reads it)")
            if len(buffer) - position < PREFIX:
                if self.recover:
                    return self._finish_cut(position)
                raise McapError(position, f"a record starts here but the file ends {len(buffer) - position} bytes "
                                          f"later, inside its 9-byte opcode and length")
            opcode = buffer[position]
            length = struct.unpack_from("<Q", buffer, position + 1)[0]
            if opcode == 0 and self.recover and not any(buffer[position:]):
                # A crash can leave a zero-filled tail where the file system had allocated blocks.
                return self._finish_cut(position)
            if length > len(buffer) - position - PREFIX:
                if self.recover:
                    return self._finish_cut(position)
                raise McapError(position, f"{self._name(opcode)} record of {length} bytes runs past the end of the "
                                          f"file ({len(buffer) - position - PREFIX} bytes left)")
            self.file.records.append(Record(opcode, position, length))
            self._record(opcode, position, position + PREFIX, position + PREFIX + length)
            position += PREFIX + length

        # The Footer was read: the summary is complete, and the closing magic follows and ends the file.
        self._check_summary()
        tail = bytes(buffer[position:position + len(MAGIC)])
        if self.recover and len(tail) < len(MAGIC) and MAGIC.startswith(tail) and position + len(tail) == len(buffer):
            self.file.cut_at = position
            return self.file
        if tail != MAGIC:
            raise McapError(position, f"the Footer is not followed by the closing magic ({tail.hex(' ')})")
        if position + len(MAGIC) != len(buffer):
            raise McapError(position + len(MAGIC), f"{len(buffer) - position - len(MAGIC)} bytes after the closing "
                                                   f"magic")
        return self.file

    def _finish_cut(self, position):
        self.file.cut_at = position
        if self.section in ("summary", "summary offsets"):
            self._check_statistics()
        return self.file

    @staticmethod
    def _name(opcode):
        return f"{NAMES[opcode]} (0x{opcode:02x})" if opcode in NAMES else f"opcode 0x{opcode:02x}"

    def _record(self, opcode, offset, start, end):
        name = self._name(opcode)
        if opcode == 0:
            raise McapError(offset, "record with opcode 0x00, which the specification makes invalid")
        if self.section == "start":
            if opcode != HEADER:
                raise McapError(offset, f"the first record is {name}; an MCAP file starts with a Header")
            fields = Fields(self.buffer, start, end, offset, "Header")
            self.file.header = Header(fields.string("profile"), fields.string("library"))
            self.section = "data"
            return
        if opcode == HEADER:
            raise McapError(offset, "a second Header record")
        if opcode == FOOTER:
            self._footer(offset, start, end)
            return
        if opcode not in NAMES:
            # 0x10-0x7f are reserved for future versions, 0x80-0xff for applications: skipped.
            self.file.ignored.append(f"offset {offset}: unknown {name} record skipped")
            return
        if self.section == "data":
            if opcode == DATA_END:
                fields = Fields(self.buffer, start, end, offset, "Data End")
                self.file.data_end_crc = fields.u32("data_section_crc")
                if self.file.data_end_crc != 0:
                    actual = zlib.crc32(self.buffer[:offset])
                    if actual != self.file.data_end_crc:
                        raise McapError(offset, f"Data End: the data section's CRC-32 is 0x{actual:08x}, the "
                                                f"record says 0x{self.file.data_end_crc:08x}")
                self.data_end_offset = offset
                self.section = "summary"
                return
            if opcode not in DATA_SECTION:
                raise McapError(offset, f"{name} record in the data section (before Data End)")
            self._data_record(opcode, offset, start, end, in_chunk=False)
            return
        if self.section == "summary" and opcode in SUMMARY_SECTION:
            self._summary_record(opcode, offset, start, end)
            return
        if opcode == SUMMARY_OFFSET:
            self.section = "summary offsets"
            if self.first_summary_offset is None:
                self.first_summary_offset = offset
            fields = Fields(self.buffer, start, end, offset, "Summary Offset")
            self.file.summary_offsets.append(SummaryOffset(fields.u8("group_opcode"), fields.u64("group_start"),
                                                           fields.u64("group_length")))
            return
        raise McapError(offset, f"{name} record in the {self.section} section")

    def _data_record(self, opcode, offset, start, end, in_chunk):
        file = self.file
        fields = Fields(self.buffer, start, end, offset, NAMES[opcode])
        if opcode == SCHEMA:
            schema = Schema(fields.u16("id"), fields.string("name"), fields.string("encoding"),
                            fields.bytes32("data"))
            if schema.id == 0:
                file.ignored.append(f"offset {offset}: Schema record with id 0 skipped (the specification "
                                    f"makes it invalid)")
                return
            self._remember(self.schema_records, "Schema", schema.id, offset, start, fields.position)
            file.schemas.setdefault(schema.id, schema)
        elif opcode == CHANNEL:
            channel = Channel(fields.u16("id"), fields.u16("schema_id"), fields.string("topic"),
                              fields.string("message_encoding"), fields.string_map("metadata"))
            if channel.schema_id != 0 and channel.schema_id not in file.schemas:
                raise McapError(offset, f"Channel {channel.id} ('{channel.topic}') names schema "
                                        f"{channel.schema_id}, which no earlier Schema record defines")
            self._remember(self.channel_records, "Channel", channel.id, offset, start, fields.position)
            file.channels.setdefault(channel.id, channel)
        elif opcode == MESSAGE:
            channel_id = fields.u16("channel_id")
            message = Message(channel_id, fields.u32("sequence"), fields.u64("log_time"),
                              fields.u64("publish_time"), fields.rest(), offset)
            if channel_id not in file.channels:
                raise McapError(offset, f"Message on channel {channel_id}, which no earlier Channel record defines")
            file.messages.append(message)
        elif in_chunk:
            raise McapError(offset, f"{NAMES[opcode]} record inside a chunk (only Schema, Channel and Message "
                                    f"may be there)")
        elif opcode == CHUNK:
            self._chunk(fields, offset)
        elif opcode == MESSAGE_INDEX:
            fields.u16("channel_id")
            fields.u64_pairs("records")
        elif opcode == ATTACHMENT:
            fields.u64("log_time")
            fields.u64("create_time")
            fields.string("name")
            fields.string("media_type")
            fields.bytes64("data")
            covered = fields.position
            crc = fields.u32("crc")
            if crc != 0 and zlib.crc32(self.buffer[start:covered]) != crc:
                raise McapError(offset, f"Attachment: CRC-32 0x{zlib.crc32(self.buffer[start:covered]):08x}, the "
                                        f"record says 0x{crc:08x}")
            file.attachment_count += 1
        elif opcode == METADATA:
            fields.string("name")
            fields.string_map("metadata")
            file.metadata_count += 1

    def _remember(self, records, what, record_id, offset, start, end):
        """Any two records with one id must be identical (their known fields)."""
        content = bytes(self.buffer[start:end])
        if record_id in records and records[record_id][0] != content:
            raise McapError(offset, f"{what} {record_id} differs from the {what} record with that id at offset "
                                    f"{records[record_id][1]}")
        records.setdefault(record_id, (content, offset))

    def _chunk(self, fields, offset):
        fields.u64("message_start_time")
        fields.u64("message_end_time")
        uncompressed_size = fields.u64("uncompressed_size")
        uncompressed_crc = fields.u32("uncompressed_crc")
        compression = fields.string("compression")
        records_length = fields.u64("records length")
        records_start = fields._take(records_length, "records")
        if compression != "":
            raise McapError(offset, f"Chunk compressed with '{compression}': this reader reads uncompressed "
                                    f"chunks only")
        if records_length != uncompressed_size:
            raise McapError(offset, f"Chunk: {records_length} bytes of records, uncompressed_size says "
                                    f"{uncompressed_size}")
        records = self.buffer[records_start:records_start + records_length]
        if uncompressed_crc != 0 and zlib.crc32(records) != uncompressed_crc:
            raise McapError(offset, f"Chunk: CRC-32 0x{zlib.crc32(records):08x}, the record says "
                                    f"0x{uncompressed_crc:08x}")
        position = records_start
        end = records_start + records_length
        while position < end:
            if end - position < PREFIX:
                raise McapError(position, "a record inside the chunk is cut in its opcode and length")
            opcode = self.buffer[position]
            length = struct.unpack_from("<Q", self.buffer, position + 1)[0]
            if length > end - position - PREFIX:
                raise McapError(position, f"{self._name(opcode)} record of {length} bytes runs past the end of "
                                          f"its chunk")
            if opcode in (SCHEMA, CHANNEL, MESSAGE):
                self._data_record(opcode, position, position + PREFIX, position + PREFIX + length, in_chunk=True)
            elif opcode in NAMES or opcode == 0:
                raise McapError(position, f"{self._name(opcode)} record inside a chunk")
            position += PREFIX + length
        self.file.chunk_count += 1

    def _summary_record(self, opcode, offset, start, end):
        if self.summary_groups and self.summary_groups[-1][0] == opcode:
            self.summary_groups[-1][2] = offset + PREFIX + (end - start) - self.summary_groups[-1][1]
        else:
            if opcode in self.seen_opcodes_in_summary:
                raise McapError(offset, f"{NAMES[opcode]} record apart from the others of its kind: the summary "
                                        f"section groups records by opcode")
            self.seen_opcodes_in_summary.add(opcode)
            self.summary_groups.append([opcode, offset, PREFIX + end - start])
        fields = Fields(self.buffer, start, end, offset, NAMES[opcode])
        if opcode == SCHEMA:
            schema = Schema(fields.u16("id"), fields.string("name"), fields.string("encoding"),
                            fields.bytes32("data"))
            self._same_as_data_section(self.schema_records, "Schema", schema.id, offset, start, fields.position)
            self.file.summary_schemas[schema.id] = schema
        elif opcode == CHANNEL:
            channel = Channel(fields.u16("id"), fields.u16("schema_id"), fields.string("topic"),
                              fields.string("message_encoding"), fields.string_map("metadata"))
            self._same_as_data_section(self.channel_records, "Channel", channel.id, offset, start, fields.position)
            self.file.summary_channels[channel.id] = channel
        elif opcode == STATISTICS:
            if self.file.statistics is not None:
                raise McapError(offset, "a second Statistics record (a file has at most one)")
            self.file.statistics = Statistics(
                fields.u64("message_count"), fields.u16("schema_count"), fields.u32("channel_count"),
                fields.u32("attachment_count"), fields.u32("metadata_count"), fields.u32("chunk_count"),
                fields.u64("message_start_time"), fields.u64("message_end_time"),
                fields.u16_u64_map("channel_message_counts"))
            self.statistics_offset = offset
            if self.file.statistics.channel_message_counts:
                missing = sorted(set(self.file.channels) - set(self.file.summary_channels))
                if missing:
                    raise McapError(offset, f"Statistics with per-channel counts, but the summary has no Channel "
                                            f"record for channel(s) {missing} before it")
        elif opcode == CHUNK_INDEX:
            for field in ("message_start_time", "message_end_time", "chunk_start_offset", "chunk_length"):
                fields.u64(field)
            fields.u16_u64_map("message_index_offsets")
            fields.u64("message_index_length")
            fields.string("compression")
            fields.u64("compressed_size")
            fields.u64("uncompressed_size")
        elif opcode == ATTACHMENT_INDEX:
            for field in ("offset", "length", "log_time", "create_time", "data_size"):
                fields.u64(field)
            fields.string("name")
            fields.string("media_type")
        elif opcode == METADATA_INDEX:
            fields.u64("offset")
            fields.u64("length")
            fields.string("name")

    def _same_as_data_section(self, records, what, record_id, offset, start, end):
        if record_id not in records:
            raise McapError(offset, f"summary {what} {record_id} is in no {what} record of the data section")
        if records[record_id][0] != bytes(self.buffer[start:end]):
            raise McapError(offset, f"summary {what} {record_id} differs from the data section's at offset "
                                    f"{records[record_id][1]}")

    def _footer(self, offset, start, end):
        if end - start != FOOTER_CONTENT:
            raise McapError(offset, f"Footer of {end - start} bytes; it has exactly {FOOTER_CONTENT}")
        fields = Fields(self.buffer, start, end, offset, "Footer")
        self.file.footer = Footer(fields.u64("summary_start"), fields.u64("summary_offset_start"),
                                  fields.u32("summary_crc"))
        self.footer_offset = offset
        self.section = "end"

    # --- the summary against the data ---------------------------------------------------------

    def _check_summary(self):
        footer = self.file.footer
        offset = self.footer_offset
        first_summary = self.summary_groups[0][1] if self.summary_groups else 0
        if footer.summary_start != first_summary:
            raise McapError(offset, f"Footer: summary_start is {footer.summary_start}, the summary section starts "
                                    f"at {first_summary}")
        if footer.summary_start != 0 and self.data_end_offset is None:
            raise McapError(offset, "Footer: a summary section but no Data End record before it")
        first_offset = self.first_summary_offset or 0
        if footer.summary_offset_start != first_offset:
            raise McapError(offset, f"Footer: summary_offset_start is {footer.summary_offset_start}, the Summary "
                                    f"Offset records start at {first_offset}")
        if footer.summary_crc != 0:
            crc_start = footer.summary_start or footer.summary_offset_start or offset
            actual = zlib.crc32(self.buffer[crc_start:offset + PREFIX + 16])
            if actual != footer.summary_crc:
                raise McapError(offset, f"Footer: the summary's CRC-32 is 0x{actual:08x}, the footer says "
                                        f"0x{footer.summary_crc:08x}")
        groups = {opcode: (start, length) for opcode, start, length in self.summary_groups}
        for summary_offset in self.file.summary_offsets:
            opcode = summary_offset.group_opcode
            where = (summary_offset.group_start, summary_offset.group_length)
            if groups.get(opcode) != where:
                actual = f"at {groups[opcode][0]}, {groups[opcode][1]} bytes" if opcode in groups else "absent"
                raise McapError(self.first_summary_offset,
                                f"Summary Offset for {self._name(opcode)}: group at {where[0]}, {where[1]} bytes; "
                                f"the summary has it {actual}")
        self._check_statistics()

    def _check_statistics(self):
        statistics = self.file.statistics
        if statistics is None:
            return
        file = self.file
        times = [m.log_time for m in file.messages]
        counts = {}
        for message in file.messages:
            counts[message.channel_id] = counts.get(message.channel_id, 0) + 1
        expected = {
            "message_count": len(file.messages),
            "schema_count": len(file.schemas),
            "channel_count": len(file.channels),
            "attachment_count": file.attachment_count,
            "metadata_count": file.metadata_count,
            "chunk_count": file.chunk_count,
            "message_start_time": min(times) if times else 0,
            "message_end_time": max(times) if times else 0,
        }
        for field, value in expected.items():
            if getattr(statistics, field) != value:
                raise McapError(self.statistics_offset, f"Statistics: {field} is {getattr(statistics, field)}, "
                                                        f"the file holds {value}")
        if statistics.channel_message_counts:
            for channel_id, count in statistics.channel_message_counts.items():
                if channel_id not in file.channels:
                    raise McapError(self.statistics_offset, f"Statistics: a count for channel {channel_id}, which "
                                                            f"the file does not define")
                if count != counts.get(channel_id, 0):
                    raise McapError(self.statistics_offset, f"Statistics: channel {channel_id} has {count} "
                                                            f"messages, the file holds {counts.get(channel_id, 0)}")
            uncounted = sorted(set(counts) - set(statistics.channel_message_counts))
            if uncounted:
                raise McapError(self.statistics_offset, f"Statistics: no count for channel(s) {uncounted}, which "
                                                        f"have messages")


def read_bytes(buffer, recover=False):
    """Reads an MCAP file from bytes. Strict (default): the file must be complete and valid. recover: reads
    every complete record of a file that was cut (no footer), cut_at says where; complete records are
    still checked and a malformed one still raises McapError."""
    return _Reader(memoryview(buffer), recover).read()


def read_file(path, recover=False):
    with open(path, "rb") as f:
        return read_bytes(f.read(), recover)


def _seconds(ns):
    return f"{ns // 1_000_000_000}.{ns % 1_000_000_000:09d}"


def describe(file):
    """The summary the command prints: schemas, channels, messages per topic, time range."""
    lines = [f"library: '{file.header.library}', profile: '{file.header.profile}', {file.size} bytes"
             if file.header else f"{file.size} bytes, no complete Header"]
    if file.closed:
        lines.append("closed: footer, summary and statistics checked" if file.statistics
                     else "closed: footer checked (no statistics)")
    elif file.cut_at is not None:
        lines.append(f"not closed: cut at byte {file.cut_at}; every record before it was read")
    lines.append(f"schemas: {len(file.schemas)}")
    for schema in file.schemas.values():
        lines.append(f"  {schema.id}: {schema.name} ({schema.encoding or 'no encoding'}, {len(schema.data)} bytes)")
    per_channel = {}
    for message in file.messages:
        per_channel[message.channel_id] = per_channel.get(message.channel_id, 0) + 1
    lines.append(f"channels: {len(file.channels)}")
    for channel in file.channels.values():
        schema = file.schemas.get(channel.schema_id)
        schema_text = f"schema {schema.id} {schema.name}" if schema else "no schema"
        metadata = f", metadata {channel.metadata}" if channel.metadata else ""
        lines.append(f"  {channel.id}: {channel.topic} [{channel.message_encoding}] {schema_text}, "
                     f"{per_channel.get(channel.id, 0)} messages{metadata}")
    per_topic = {}
    for channel_id, count in per_channel.items():
        topic = file.channels[channel_id].topic
        per_topic[topic] = per_topic.get(topic, 0) + count
    lines.append(f"messages: {len(file.messages)}")
    for topic, count in sorted(per_topic.items()):
        lines.append(f"  {topic}: {count}")
    if file.messages:
        start = min(m.log_time for m in file.messages)
        end = max(m.log_time for m in file.messages)
        lines.append(f"log time: {_seconds(start)} .. {_seconds(end)} s ({_seconds(end - start)} s)")
    for note in file.ignored:
        lines.append(f"ignored: {note}")
    return "\n".join(lines)


def main(argv):
    parser = argparse.ArgumentParser(description="Reads and checks an MCAP file; prints its summary.")
    parser.add_argument("file")
    parser.add_argument("--recover", action="store_true",
                        help="read every complete record of a file that was not closed (cut, crashed writer)")
    parser.add_argument("--list", action="store_true", help="also print every message")
    args = parser.parse_args(argv)
    try:
        file = read_file(args.file, recover=args.recover)
    except McapError as e:
        print(f"error: {args.file}: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"error: {args.file}: {e.strerror}", file=sys.stderr)
        return 1
    print(f"{args.file}: {describe(file)}")
    if args.list:
        for m in file.messages:
            print(f"  @{m.offset} {file.channels[m.channel_id].topic} seq {m.sequence} log {_seconds(m.log_time)} "
                  f"publish {_seconds(m.publish_time)} {len(m.data)} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

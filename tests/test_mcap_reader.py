#!/usr/bin/env python3
"""The MCAP files the McapWriter writes, read back by the independent reader (tests/mcap_reader.py):
every schema, channel and message the writer was given (tests/mcap_sample_writer.cpp writes a
manifest of them) comes back with its ids, times and payload, and the summary agrees with it. Files
cut at every byte, copied before close, left by a killed writer or stopped by a full file give
every message written before the cut in recover mode and an error naming the offset in strict mode.
The reader itself fails on malformed files, each with the offset of the problem.

    python3 tests/test_mcap_reader.py --writer build/release/bin/mcap_sample_writer
"""

import json
import pathlib
import signal
import struct
import subprocess
import sys
import tempfile
import unittest
import zlib

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import mcap_reader  # noqa: E402

READER = pathlib.Path(__file__).resolve().parent / "mcap_reader.py"
WRITER = None  # set from --writer


def write_sample(folder, plan, *extra):
    """Runs the sample writer; returns (mcap path, manifest, the process's return code)."""
    mcap = pathlib.Path(folder) / f"{plan}.mcap"
    manifest = pathlib.Path(folder) / f"{plan}.json"
    result = subprocess.run([WRITER, plan, str(mcap), str(manifest), *map(str, extra)], capture_output=True,
                            text=True)
    if result.returncode not in (0, -signal.SIGKILL):
        raise AssertionError(f"mcap_sample_writer {plan} failed ({result.returncode}): {result.stderr}")
    with open(manifest) as f:
        return mcap, json.load(f), result.returncode


class McapCase(unittest.TestCase):
    def assert_matches_manifest(self, file, manifest, messages=None):
        """The file holds exactly the manifest's schemas and channels, and its messages (or `messages`)."""
        expected_messages = manifest["messages"] if messages is None else messages
        self.assertEqual(file.header.library, manifest["library"])
        self.assertEqual(file.header.profile, "")
        for schema in manifest["schemas"]:
            got = file.schemas[schema["id"]]
            self.assertEqual((got.name, got.encoding, got.data.hex()),
                             (schema["name"], schema["encoding"], schema["data"]))
        for channel in manifest["channels"]:
            got = file.channels[channel["id"]]
            self.assertEqual((got.schema_id, got.topic, got.message_encoding, got.metadata),
                             (channel["schema_id"], channel["topic"], channel["message_encoding"],
                              channel["metadata"]))
        self.assertEqual(len(file.messages), len(expected_messages))
        for index, (got, want) in enumerate(zip(file.messages, expected_messages)):
            with self.subTest(message=index):
                self.assertEqual((got.channel_id, got.sequence, got.log_time, got.publish_time),
                                 (want["channel_id"], want["sequence"], want["log_time"], want["publish_time"]))
                self.assertEqual(got.data.hex(), want["data"])

    def assert_statistics(self, file, manifest):
        """The summary's own numbers (the reader checks them against the records; these against the manifest)."""
        stats = file.statistics
        messages = manifest["messages"]
        self.assertEqual(stats.message_count, len(messages))
        self.assertEqual(stats.schema_count, len(manifest["schemas"]))
        self.assertEqual(stats.channel_count, len(manifest["channels"]))
        self.assertEqual(stats.chunk_count, 0)
        self.assertEqual(stats.message_start_time, min((m["log_time"] for m in messages), default=0))
        self.assertEqual(stats.message_end_time, max((m["log_time"] for m in messages), default=0))
        for channel in manifest["channels"]:
            count = sum(1 for m in messages if m["channel_id"] == channel["id"])
            self.assertEqual(stats.channel_message_counts[channel["id"]], count)
        self.assertEqual(set(file.summary_schemas), {s["id"] for s in manifest["schemas"]})
        self.assertEqual(set(file.summary_channels), {c["id"] for c in manifest["channels"]})


class ClosedFiles(McapCase):
    def test_full_round_trip(self):
        with tempfile.TemporaryDirectory() as folder:
            path, manifest, _ = write_sample(folder, "full")
            self.assertTrue(manifest["closed"], manifest["error"])
            file = mcap_reader.read_file(path)
            self.assertTrue(file.closed)
            self.assertEqual(file.size, manifest["bytes_written"])
            self.assert_matches_manifest(file, manifest)
            self.assert_statistics(file, manifest)
            # Unchunked, with both CRCs, and a Summary Offset for each group of the summary.
            self.assertEqual(file.chunk_count, 0)
            self.assertNotEqual(file.data_end_crc, 0)
            self.assertNotEqual(file.footer.summary_crc, 0)
            self.assertEqual([o.group_opcode for o in file.summary_offsets],
                             [mcap_reader.SCHEMA, mcap_reader.CHANNEL, mcap_reader.STATISTICS])
            sizes = sorted(len(m.data) for m in file.messages)
            self.assertEqual(sizes[0], 0)
            self.assertEqual(sizes[-1], (4 << 20) + 3)
            self.assertEqual(file.ignored, [])

    def test_many_channels(self):
        with tempfile.TemporaryDirectory() as folder:
            path, manifest, _ = write_sample(folder, "many")
            file = mcap_reader.read_file(path)
            self.assertEqual(len(file.channels), 1000)
            self.assert_matches_manifest(file, manifest)
            self.assert_statistics(file, manifest)

    def test_command_prints_the_summary(self):
        with tempfile.TemporaryDirectory() as folder:
            path, _, _ = write_sample(folder, "small")
            result = subprocess.run([sys.executable, str(READER), str(path)], capture_output=True, text=True)
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertIn("library: 'voca-rt tests/mcap_sample_writer'", result.stdout)
            self.assertIn("closed: footer, summary and statistics checked", result.stdout)
            self.assertIn("  /odom: 6\n", result.stdout)
            self.assertIn("  /raw: 6\n", result.stdout)
            self.assertIn("  /late: 1\n", result.stdout)
            self.assertIn("log time: 0.900000000 .. 1.250000001 s", result.stdout)
            self.assertIn("1: foxglove.PoseInFrame (jsonschema", result.stdout)


class CutFiles(McapCase):
    def test_cut_at_every_byte(self):
        """Recover mode gives exactly the messages whose records end before the cut; strict mode refuses."""
        with tempfile.TemporaryDirectory() as folder:
            path, manifest, _ = write_sample(folder, "small")
            data = path.read_bytes()
            closed = mcap_reader.read_bytes(data)
            data_end = next(r.offset for r in closed.records if r.opcode == mcap_reader.DATA_END)
            message_ends = [m.offset + mcap_reader.PREFIX + 22 + len(m.data) for m in closed.messages]
            for cut in range(len(data)):
                with self.subTest(cut=cut):
                    with self.assertRaises(mcap_reader.McapError):
                        mcap_reader.read_bytes(data[:cut])
                    file = mcap_reader.read_bytes(data[:cut], recover=True)
                    complete = sum(1 for end in message_ends if end <= cut)
                    self.assertEqual(len(file.messages), complete)
                    self.assertFalse(file.closed)
                    if cut <= data_end:
                        self.assertIsNotNone(file.cut_at)
                        self.assertLessEqual(file.cut_at, cut)
            self.assert_matches_manifest(mcap_reader.read_bytes(data[:data_end], recover=True), manifest)

    def test_copy_before_close(self):
        with tempfile.TemporaryDirectory() as folder:
            copy = pathlib.Path(folder) / "before-close.mcap"
            path, manifest, _ = write_sample(folder, "copy", copy)
            copied = manifest["messages"][:manifest["copied_messages"]]
            self.assertEqual(len(copied), 40)
            with self.assertRaises(mcap_reader.McapError) as raised:
                mcap_reader.read_file(copy)
            self.assertIn("without a Footer", str(raised.exception))
            recovered = mcap_reader.read_file(copy, recover=True)
            self.assertEqual(recovered.cut_at, copy.stat().st_size)  # it ends after a complete record
            self.assert_matches_manifest(recovered, {**manifest, "channels": manifest["channels"][:1]}, copied)
            closed = mcap_reader.read_file(path)
            self.assert_matches_manifest(closed, manifest)
            self.assert_statistics(closed, manifest)

    def test_killed_writer(self):
        with tempfile.TemporaryDirectory() as folder:
            path, manifest, returncode = write_sample(folder, "killed")
            self.assertEqual(returncode, -signal.SIGKILL)
            self.assertEqual(len(manifest["messages"]), 60)
            with self.assertRaises(mcap_reader.McapError):
                mcap_reader.read_file(path)
            file = mcap_reader.read_file(path, recover=True)
            self.assert_matches_manifest(file, manifest)
            result = subprocess.run([sys.executable, str(READER), "--recover", str(path)], capture_output=True,
                                    text=True)
            self.assertEqual(result.returncode, 0, result.stderr)
            self.assertIn(f"not closed: cut at byte {path.stat().st_size}", result.stdout)
            result = subprocess.run([sys.executable, str(READER), str(path)], capture_output=True, text=True)
            self.assertEqual(result.returncode, 1)
            self.assertIn(f"error: {path}: offset {path.stat().st_size}:", result.stderr)

    def test_file_size_limit_mid_record(self):
        """A write the OS refuses halfway (as on a full disk): every message reported written is in the file."""
        with tempfile.TemporaryDirectory() as folder:
            path, manifest, _ = write_sample(folder, "file-limit")
            self.assertFalse(manifest["closed"])
            self.assertIn(str(path), manifest["error"])
            self.assertIn("File too large", manifest["error"])
            self.assertGreater(manifest["refused_writes"], 0)
            self.assertEqual(path.stat().st_size, 20000)
            file = mcap_reader.read_file(path, recover=True)
            self.assert_matches_manifest(file, manifest)
            self.assertLess(file.cut_at, 20000)  # the refused message's record is cut


def record_offsets(file, opcode):
    return [r.offset for r in file.records if r.opcode == opcode]


class MalformedFiles(unittest.TestCase):
    """The reader can fail: each damage is found, named with its offset."""

    @classmethod
    def setUpClass(cls):
        cls.folder = tempfile.TemporaryDirectory()
        path, _, _ = write_sample(cls.folder.name, "small")
        cls.data = path.read_bytes()
        cls.file = mcap_reader.read_bytes(cls.data)

    @classmethod
    def tearDownClass(cls):
        cls.folder.cleanup()

    def damaged(self, offset, new_bytes):
        data = bytearray(self.data)
        data[offset:offset + len(new_bytes)] = new_bytes
        return data

    def assert_error(self, data, offset, text, recover=False):
        with self.assertRaises(mcap_reader.McapError) as raised:
            mcap_reader.read_bytes(data, recover=recover)
        self.assertEqual(raised.exception.offset, offset, str(raised.exception))
        self.assertIn(text, str(raised.exception))

    def without_summary_crc(self, data):
        """The footer's CRC set to 0 ("not computed"), so a damage in the summary reaches the other checks."""
        footer = record_offsets(self.file, mcap_reader.FOOTER)[0]
        data[footer + mcap_reader.PREFIX + 16:footer + mcap_reader.PREFIX + 20] = b"\0\0\0\0"
        return data

    def test_magic(self):
        self.assert_error(self.damaged(1, b"X"), 0, "not an MCAP file")
        self.assert_error(self.damaged(len(self.data) - 1, b"X"), len(self.data) - 8, "closing magic")
        self.assert_error(self.data + b"\0", len(self.data), "1 bytes after the closing magic")

    def test_record_longer_than_the_file(self):
        message = self.file.messages[0].offset
        data = self.damaged(message + 1, struct.pack("<Q", 1 << 40))
        self.assert_error(data, message, "runs past the end of the file")
        recovered = mcap_reader.read_bytes(data, recover=True)  # what a reader after a crash cannot tell apart
        self.assertEqual(recovered.cut_at, message)

    def test_string_longer_than_its_record(self):
        channel = record_offsets(self.file, mcap_reader.CHANNEL)[0]
        # The topic's length field, after the opcode, the length and two ids.
        data = self.damaged(channel + mcap_reader.PREFIX + 4, struct.pack("<I", 10_000))
        self.assert_error(data, channel, "topic needs 10000 bytes", recover=True)

    def test_message_on_an_unknown_channel(self):
        message = self.file.messages[0].offset
        data = self.damaged(message + mcap_reader.PREFIX, struct.pack("<H", 77))
        self.assert_error(data, message, "channel 77, which no earlier Channel record defines", recover=True)

    def test_channel_on_an_unknown_schema(self):
        channel = record_offsets(self.file, mcap_reader.CHANNEL)[0]
        data = self.damaged(channel + mcap_reader.PREFIX + 2, struct.pack("<H", 9))
        self.assert_error(data, channel, "names schema 9", recover=True)

    def test_data_section_crc(self):
        message = self.file.messages[0]
        data = self.damaged(message.offset + mcap_reader.PREFIX + 22, b"\xff")
        data_end = record_offsets(self.file, mcap_reader.DATA_END)[0]
        self.assert_error(data, data_end, "data section's CRC-32")

    def test_summary_crc(self):
        statistics = record_offsets(self.file, mcap_reader.STATISTICS)[0]
        data = self.damaged(statistics + mcap_reader.PREFIX, struct.pack("<Q", 3))
        footer = record_offsets(self.file, mcap_reader.FOOTER)[0]
        self.assert_error(data, footer, "summary's CRC-32")

    def test_statistics_against_the_records(self):
        statistics = record_offsets(self.file, mcap_reader.STATISTICS)[0]
        content = statistics + mcap_reader.PREFIX
        data = self.without_summary_crc(self.damaged(content, struct.pack("<Q", 12)))
        self.assert_error(data, statistics, "message_count is 12, the file holds 13")
        data = self.without_summary_crc(self.damaged(content + 26, struct.pack("<Q", 1)))
        self.assert_error(data, statistics, "message_start_time is 1, the file holds 900000000")
        # The per-channel map: entries of channel id (2 bytes) and count (8), after the 46 fixed bytes.
        data = self.without_summary_crc(self.damaged(content + 46 + 2, struct.pack("<Q", 5)))
        self.assert_error(data, statistics, "channel 1 has 5 messages, the file holds 6")

    def test_summary_copy_differs(self):
        summary_channel = record_offsets(self.file, mcap_reader.CHANNEL)[-1]
        data = self.without_summary_crc(self.damaged(summary_channel + mcap_reader.PREFIX + 8, b"X"))
        self.assert_error(data, summary_channel, "differs from the data section's")

    def test_summary_offset_and_footer_offsets(self):
        summary_offset = record_offsets(self.file, mcap_reader.SUMMARY_OFFSET)[0]
        data = self.without_summary_crc(self.damaged(summary_offset + mcap_reader.PREFIX + 9, struct.pack("<Q", 1)))
        self.assert_error(data, summary_offset, "Summary Offset for Schema")
        footer = record_offsets(self.file, mcap_reader.FOOTER)[0]
        data = self.without_summary_crc(self.damaged(footer + mcap_reader.PREFIX, struct.pack("<Q", 8)))
        self.assert_error(data, footer, "summary_start is 8")

    def test_invalid_and_misplaced_records(self):
        message = self.file.messages[0].offset
        self.assert_error(self.damaged(message, b"\x00"), message, "opcode 0x00", recover=True)
        self.assert_error(self.damaged(message, bytes([mcap_reader.STATISTICS])), message,
                          "Statistics (0x0b) record in the data section", recover=True)
        header_end = 8 + mcap_reader.PREFIX + struct.unpack_from("<Q", self.data, 9)[0]
        self.assert_error(self.damaged(8, bytes([mcap_reader.SCHEMA])), 8, "starts with a Header", recover=True)
        self.assert_error(self.damaged(header_end, bytes([mcap_reader.HEADER])), header_end, "a second Header",
                          recover=True)

    def test_unknown_opcodes_are_skipped(self):
        """Opcodes 0x80-0xff belong to applications: a reader skips them (spec), here after the Header."""
        header_end = 8 + mcap_reader.PREFIX + struct.unpack_from("<Q", self.data, 9)[0]
        data_end = record_offsets(self.file, mcap_reader.DATA_END)[0]
        extra = bytes([0x80]) + struct.pack("<Q", 3) + b"abc"
        # Up to Data End only: the records after the insert moved, so the summary's offsets no longer match.
        data = self.data[:header_end] + extra + self.data[header_end:data_end]
        file = mcap_reader.read_bytes(data, recover=True)
        self.assertEqual(len(file.messages), len(self.file.messages))
        self.assertEqual(len(file.ignored), 1)
        self.assertIn(f"offset {header_end}: unknown opcode 0x80", file.ignored[0])

    def test_zero_filled_tail_is_a_cut_in_recover_mode(self):
        data_end = record_offsets(self.file, mcap_reader.DATA_END)[0]
        data = self.data[:data_end] + bytes(4096)
        file = mcap_reader.read_bytes(data, recover=True)
        self.assertEqual(file.cut_at, data_end)
        self.assertEqual(len(file.messages), len(self.file.messages))
        self.assert_error(data, data_end, "opcode 0x00")

    def test_reader_crc_is_zlib_crc(self):
        """The CRC the reader checks is zlib's CRC-32 (the specification's); the writer's matches it."""
        data_end = record_offsets(self.file, mcap_reader.DATA_END)[0]
        self.assertEqual(self.file.data_end_crc, zlib.crc32(self.data[:data_end]))


def main():
    global WRITER
    args = sys.argv[1:]
    if len(args) < 2 or args[0] != "--writer":
        print("usage: test_mcap_reader.py --writer <mcap_sample_writer> [unittest arguments]", file=sys.stderr)
        return 2
    WRITER = args[1]
    program = unittest.main(argv=[sys.argv[0], *args[2:]], exit=False)
    return 0 if program.result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())

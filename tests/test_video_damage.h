#pragma once
// Damaging a video in place, as a disk or network would: the tests of what the decoder, `voca run`
// and `voca mv` make of it.

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "drivers/decode/demuxer.h"

namespace voca::test {

// Overwrites the slice data of packet `index` of a video with noise, in place.
inline void damagePacket(const std::filesystem::path& video, int index) {
  decode::Demuxer demuxer(video);
  decode::Packet packet;
  for (int i = 0; i <= index; ++i) REQUIRE(demuxer.read(packet));
  std::string bytes;
  {
    std::ifstream in(video, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string needle(packet.bytes.begin(), packet.bytes.begin() + std::min<std::size_t>(64, packet.bytes.size()));
  const std::size_t at = bytes.find(needle);
  REQUIRE(at != std::string::npos);
  std::mt19937 rng(5);
  // Past the 4-byte length prefix and the slice header's first bytes: the macroblock data is garbage.
  for (std::size_t i = at + 12; i < at + packet.bytes.size(); ++i) bytes[i] = static_cast<char>(rng());
  std::ofstream(video, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace voca::test

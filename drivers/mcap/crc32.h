#pragma once
// CRC-32 as MCAP (and zlib, PNG, Ethernet) use it: reflected polynomial 0xEDB88320, register
// starting at all ones, result inverted. MCAP stores it for the data section, the summary, chunks
// and attachments; 0 there means "not computed".

#include <cstdint>
#include <span>

namespace voca::mcap {

// The CRC-32 of everything passed so far: start with crc = 0 and feed the bytes in any pieces,
// crc32(crc32(0, a), b) == crc32(0, a followed by b). About 1 byte per cycle (slicing by 8).
std::uint32_t crc32(std::uint32_t crc, std::span<const std::uint8_t> bytes);

}  // namespace voca::mcap

#pragma once
// Camera pixel formats -> 8-bit gray: GREY (Y8), Y10, Y16, YUYV and NV12. The tracker only needs
// luma, so every format keeps its Y samples and drops chroma; deeper formats keep their top 8 bits.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "voca/core/image.h"

namespace voca::capture {

// True for the formats convertToGray() reads.
bool isGrayConvertible(std::uint32_t fourcc);
// The formats above, in order of preference for capture (least conversion work and bandwidth first).
const std::uint32_t* grayConvertibleFormats(std::size_t& count);
// "GREY, Y10, Y16, YUYV, NV12", for messages.
std::string grayConvertibleList();

// "GREY", "Y10", "Y16", "YUYV", "NV12" (as `voca devices` prints them) -> the fourcc; InputError
// for anything else.
std::uint32_t parseGrayConvertibleFormat(std::string_view text);

// Bytes a frame of this format needs with this line pitch (NV12: the Y plane plus half again for
// the interleaved chroma plane).
std::size_t frameBytes(std::uint32_t fourcc, std::size_t bytes_per_line, int height);

// The columns [x0, x0 + width) of a captured frame, as gray, into out (resized, so the same size
// every frame allocates nothing). data holds bytes_used bytes laid out with bytes_per_line;
// throws InputError when bytes_used is shorter than the frame needs (a truncated buffer).
void convertToGray(const std::uint8_t* data, std::size_t bytes_used, std::uint32_t fourcc, std::size_t bytes_per_line,
                   int x0, int width, int height, GrayImage& out);

}  // namespace voca::capture

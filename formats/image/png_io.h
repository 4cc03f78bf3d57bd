#pragma once
// PNG files <-> images: 8-bit gray for the tracker (any PNG converted on read), gray and RGB for output.

#include <filesystem>

#include "voca/core/image.h"

namespace voca {

// Reads any PNG as 8-bit gray into out, reusing its buffer. 16-bit samples keep their high byte
// (as OpenCV's and Basalt's 16->8 bit conversion), palette and colour images are converted to
// luma, alpha is dropped. Throws InputError naming the file when it is missing or not a valid PNG.
void readPngGray(const std::filesystem::path& path, GrayImage& out);
GrayImage readPngGray(const std::filesystem::path& path);

// Reads any PNG as packed 8-bit RGB (gray expanded, alpha dropped), e.g. to check visualisations.
void readPngRgb(const std::filesystem::path& path, RgbImage& out);

// Write 8-bit gray / RGB PNGs. Throws InputError naming the file when it cannot be written.
void writePngGray(const std::filesystem::path& path, GrayView image);
void writePngRgb(const std::filesystem::path& path, RgbView image);

}  // namespace voca

#include "formats/image/png_io.h"

#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <string>

#include "voca/core/error.h"

// libpng reports errors by longjmp. The functions that call setjmp below hold no objects with
// destructors, so a jump never skips one; the C++ exceptions are thrown only after libpng returned.

namespace voca {
namespace {

static_assert(sizeof(Rgb8) == 3, "Rgb8 rows are written to libpng as packed RGB bytes");

// Larger images are certainly corrupt headers for our use; refuse them before allocating.
constexpr png_uint_32 kMaxDimension = 1u << 15;

struct PngState {
  std::FILE* file = nullptr;
  png_structp png = nullptr;
  png_infop info = nullptr;
  bool writing = false;
  char message[256] = {};

  ~PngState() {
    if (png != nullptr) {
      if (writing) {
        png_destroy_write_struct(&png, info != nullptr ? &info : nullptr);
      } else {
        png_destroy_read_struct(&png, info != nullptr ? &info : nullptr, nullptr);
      }
    }
    if (file != nullptr) std::fclose(file);
  }
};

void onPngError(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof(state->message), "%s", message);
  png_longjmp(png, 1);
}

// Warnings (e.g. an sRGB profile libpng dislikes) do not make an image unusable.
void onPngWarning(png_structp, png_const_charp) {}

struct Header {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
};

// Sets up libpng's conversions so rows arrive as 8-bit gray (channels 1) or packed RGB (channels 3).
bool readHeader(PngState& s, Header& header, int channels) {
  if (setjmp(png_jmpbuf(s.png))) return false;
  png_init_io(s.png, s.file);
  png_set_sig_bytes(s.png, 8);
  png_set_user_limits(s.png, kMaxDimension, kMaxDimension);
  png_read_info(s.png, s.info);
  const int color_type = png_get_color_type(s.png, s.info);
  const int bit_depth = png_get_bit_depth(s.png, s.info);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(s.png);
  if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(s.png);
  if (bit_depth == 16) png_set_strip_16(s.png);
  if ((color_type & PNG_COLOR_MASK_ALPHA) != 0) png_set_strip_alpha(s.png);
  const bool colour = (color_type & PNG_COLOR_MASK_COLOR) != 0;
  if (channels == 1 && colour) {
    // error_action 1: convert silently; negative weights select libpng's default luma weights.
    png_set_rgb_to_gray_fixed(s.png, 1, -1, -1);
  }
  if (channels == 3 && !colour) png_set_gray_to_rgb(s.png);
  png_set_interlace_handling(s.png);
  png_read_update_info(s.png, s.info);
  if (png_get_channels(s.png, s.info) != channels ||
      png_get_rowbytes(s.png, s.info) != png_get_image_width(s.png, s.info) * static_cast<png_uint_32>(channels)) {
    std::snprintf(s.message, sizeof(s.message), "unsupported pixel format after conversion to 8-bit %s",
                  channels == 1 ? "gray" : "RGB");
    return false;
  }
  header.width = png_get_image_width(s.png, s.info);
  header.height = png_get_image_height(s.png, s.info);
  return true;
}

template <typename Pixel>
bool readPixels(PngState& s, Image<Pixel>& out) {
  if (setjmp(png_jmpbuf(s.png))) return false;
  // Interlaced files come in several passes over the same rows; libpng merges them in place.
  const int passes = png_set_interlace_handling(s.png);
  for (int pass = 0; pass < passes; ++pass) {
    for (int y = 0; y < out.height(); ++y) png_read_row(s.png, reinterpret_cast<png_bytep>(out.row(y)), nullptr);
  }
  png_read_end(s.png, nullptr);
  return true;
}

bool writeImage(PngState& s, const std::uint8_t* data, int width, int height, std::ptrdiff_t stride_bytes,
                int color_type) {
  if (setjmp(png_jmpbuf(s.png))) return false;
  png_init_io(s.png, s.file);
  png_set_IHDR(s.png, s.info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), 8, color_type,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // Speed over size: dataset writers produce thousands of frames.
  png_set_compression_level(s.png, 1);
  png_write_info(s.png, s.info);
  for (int y = 0; y < height; ++y) png_write_row(s.png, data + y * stride_bytes);
  png_write_end(s.png, nullptr);
  return true;
}

void writePng(const std::filesystem::path& path, const std::uint8_t* data, int width, int height,
              std::ptrdiff_t stride_bytes, int color_type) {
  if (width <= 0 || height <= 0 || data == nullptr) {
    throw InputError(path.string() + ": cannot write an empty image (" + std::to_string(width) + "x" +
                     std::to_string(height) + ")");
  }
  PngState s;
  s.writing = true;
  s.file = std::fopen(path.c_str(), "wb");
  if (s.file == nullptr) throw InputError(path.string() + ": cannot open for writing: " + std::strerror(errno));
  s.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &s, onPngError, onPngWarning);
  if (s.png != nullptr) s.info = png_create_info_struct(s.png);
  if (s.png == nullptr || s.info == nullptr) throw RuntimeFailure("libpng: out of memory");
  bool ok = writeImage(s, data, width, height, stride_bytes, color_type);
  const bool close_failed = std::fclose(s.file) != 0;
  s.file = nullptr;
  if (ok && close_failed) {
    ok = false;
    std::snprintf(s.message, sizeof(s.message), "%s", std::strerror(errno));
  }
  if (!ok) {
    std::error_code ignored;
    std::filesystem::remove(path, ignored);
    throw InputError(path.string() + ": cannot write PNG: " + s.message);
  }
}

template <typename Pixel>
void readPng(const std::filesystem::path& path, Image<Pixel>& out) {
  constexpr int kChannels = static_cast<int>(sizeof(Pixel));
  PngState s;
  s.file = std::fopen(path.c_str(), "rb");
  if (s.file == nullptr) throw InputError(path.string() + ": cannot open image: " + std::strerror(errno));
  png_byte signature[8] = {};
  if (std::fread(signature, 1, sizeof(signature), s.file) != sizeof(signature) ||
      png_sig_cmp(signature, 0, sizeof(signature)) != 0) {
    throw InputError(path.string() + ": not a PNG file (bad signature)");
  }
  s.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &s, onPngError, onPngWarning);
  if (s.png != nullptr) s.info = png_create_info_struct(s.png);
  if (s.png == nullptr || s.info == nullptr) throw RuntimeFailure("libpng: out of memory");
  Header header;
  if (!readHeader(s, header, kChannels)) throw InputError(path.string() + ": corrupt PNG: " + s.message);
  out.resize(static_cast<int>(header.width), static_cast<int>(header.height));
  if (!readPixels(s, out)) throw InputError(path.string() + ": corrupt PNG: " + s.message);
}

}  // namespace

void readPngGray(const std::filesystem::path& path, GrayImage& out) { readPng(path, out); }

void readPngRgb(const std::filesystem::path& path, RgbImage& out) { readPng(path, out); }

GrayImage readPngGray(const std::filesystem::path& path) {
  GrayImage image;
  readPngGray(path, image);
  return image;
}

void writePngGray(const std::filesystem::path& path, GrayView image) {
  writePng(path, image.data, image.width, image.height, image.stride, PNG_COLOR_TYPE_GRAY);
}

void writePngRgb(const std::filesystem::path& path, RgbView image) {
  writePng(path, reinterpret_cast<const std::uint8_t*>(image.data), image.width, image.height,
           image.stride * static_cast<std::ptrdiff_t>(sizeof(Rgb8)), PNG_COLOR_TYPE_RGB);
}

}  // namespace voca

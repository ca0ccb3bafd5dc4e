// PNG encoding and decoding with libpng's simplified API, which reports
// errors through png_image::message instead of longjmp.
#include "client/pathctl/png_io.h"

#include <png.h>

#include <cstring>
#include <fstream>
#include <string>

#include "absl/strings/str_cat.h"
#include "client/pathctl/files.h"

namespace pathd::pathctl {
namespace {

// Frees libpng's state on every return path (finish_read frees it on success
// too; png_image_free is a no-op then).
class PngImageGuard {
 public:
  PngImageGuard() {
    std::memset(&image_, 0, sizeof(image_));
    image_.version = PNG_IMAGE_VERSION;
  }
  ~PngImageGuard() { png_image_free(&image_); }
  PngImageGuard(const PngImageGuard&) = delete;
  PngImageGuard& operator=(const PngImageGuard&) = delete;

  png_image* get() { return &image_; }

 private:
  png_image image_;
};

}  // namespace

absl::StatusOr<std::string> EncodePng(const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      (image.channels != 3 && image.channels != 4) ||
      image.pixels.size() != static_cast<size_t>(image.width) *
                                 static_cast<size_t>(image.height) *
                                 static_cast<size_t>(image.channels)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "cannot encode a ", image.width, " x ", image.height, " image of ",
        image.channels, " channels from ", image.pixels.size(), " bytes"));
  }
  PngImageGuard guard;
  png_image* png = guard.get();
  png->width = static_cast<png_uint_32>(image.width);
  png->height = static_cast<png_uint_32>(image.height);
  png->format = image.channels == 4 ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
  // Two passes: the first asks for the size, the second writes.
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(png, nullptr, &size, /*convert_to_8_bit=*/0,
                                 image.pixels.data(), /*row_stride=*/0,
                                 /*colormap=*/nullptr)) {
    return absl::InternalError(absl::StrCat("libpng: ", png->message));
  }
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(png, bytes.data(), &size, 0,
                                 image.pixels.data(), 0, nullptr)) {
    return absl::InternalError(absl::StrCat("libpng: ", png->message));
  }
  bytes.resize(size);
  return bytes;
}

absl::Status WritePngFile(const Image& image, const std::string& path) {
  absl::StatusOr<std::string> bytes = EncodePng(image);
  if (!bytes.ok()) return bytes.status();
  return WriteTextFile(path, *bytes);
}

absl::StatusOr<Image> DecodePngRgba(std::string_view png_bytes,
                                    std::string_view source_in,
                                    int64_t max_pixels) {
  const std::string source(source_in);
  PngImageGuard guard;
  png_image* png = guard.get();
  if (!png_image_begin_read_from_memory(png, png_bytes.data(),
                                        png_bytes.size())) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": not a PNG image: ", png->message));
  }
  const int64_t pixels = int64_t{png->width} * int64_t{png->height};
  if (pixels > max_pixels) {
    return absl::InvalidArgumentError(absl::StrCat(
        source, ": image of ", png->width, " x ", png->height, " = ", pixels,
        " pixels exceeds the limit of ", max_pixels, " cells"));
  }
  // Without this libpng treats 16-bit samples as linear light and
  // gamma-encodes them on the way to 8 bits, moving every grey level.
  png->flags |= PNG_IMAGE_FLAG_16BIT_sRGB;
  png->format = PNG_FORMAT_RGBA;
  Image image;
  image.width = static_cast<int32_t>(png->width);
  image.height = static_cast<int32_t>(png->height);
  image.channels = 4;
  image.pixels.resize(PNG_IMAGE_SIZE(*png));
  if (!png_image_finish_read(png, /*background=*/nullptr, image.pixels.data(),
                             /*row_stride=*/0, /*colormap=*/nullptr)) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": bad PNG data: ", png->message));
  }
  return image;
}

}  // namespace pathd::pathctl

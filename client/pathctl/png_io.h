// PNG files through Debian's libpng (its simplified png_image API): encoding
// the RGB pictures `pathctl render` draws and decoding the occupancy images
// `pathctl maps import` reads. No libpng type appears here.
#ifndef PATHD_CLIENT_PATHCTL_PNG_IO_H_
#define PATHD_CLIENT_PATHCTL_PNG_IO_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace pathd::pathctl {

// An 8-bit image, row-major, top row first, `channels` bytes per pixel (3:
// RGB, 4: RGBA). A value type.
struct Image {
  int32_t width = 0;
  int32_t height = 0;
  int channels = 3;
  std::vector<uint8_t> pixels;  // width * height * channels bytes
};

// Encodes an RGB or RGBA image as PNG bytes. INVALID_ARGUMENT when the pixel
// buffer does not match the size; INTERNAL with libpng's message otherwise.
absl::StatusOr<std::string> EncodePng(const Image& image);

// Writes EncodePng's bytes to `path`; PERMISSION_DENIED / DATA_LOSS naming it.
absl::Status WritePngFile(const Image& image, const std::string& path);

// Decodes PNG bytes of any colour type and bit depth to 8-bit RGBA (grey is
// replicated, palettes expanded, a tRNS chunk becomes alpha, 16-bit samples
// are scaled, not gamma-converted: occupancy images store values, not light).
// INVALID_ARGUMENT "<source>: not a PNG image: ..." for bad data, and when
// width * height exceeds `max_pixels` (checked before decoding).
absl::StatusOr<Image> DecodePngRgba(std::string_view png,
                                    std::string_view source,
                                    int64_t max_pixels);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_PNG_IO_H_

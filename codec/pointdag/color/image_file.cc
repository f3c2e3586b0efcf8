#include "pointdag/color/image_file.h"

#include <png.h>
#include <turbojpeg.h>
#include <webp/decode.h>
#include <webp/encode.h>

#include <memory>
#include <string>

namespace pointdag {
namespace {

struct TjDeleter {
  void operator()(void* handle) const { tjDestroy(handle); }
};
using TjHandle = std::unique_ptr<void, TjDeleter>;

// libpng's simplified API keeps its state in the png_image; free it on every path.
struct PngImage {
  png_image image{};
  PngImage() { image.version = PNG_IMAGE_VERSION; }
  ~PngImage() { png_image_free(&image); }
};

StatusOr<std::vector<uint8_t>> EncodePng(std::span<const uint8_t> rgb, uint32_t side) {
  PngImage png;
  png.image.width = side;
  png.image.height = side;
  png.image.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> out(PNG_IMAGE_PNG_SIZE_MAX(png.image));
  png_alloc_size_t size = out.size();
  if (!png_image_write_to_memory(&png.image, out.data(), &size, 0, rgb.data(), 0, nullptr)) {
    return Internal(std::string("libpng: ") + png.image.message);
  }
  out.resize(size);
  return out;
}

StatusOr<std::vector<uint8_t>> DecodePng(std::span<const uint8_t> image, uint32_t side) {
  PngImage png;
  if (!png_image_begin_read_from_memory(&png.image, image.data(), image.size())) {
    return Corrupt(std::string("color PNG: ") + png.image.message);
  }
  if (png.image.width != side || png.image.height != side) return Corrupt("color image has the wrong size");
  png.image.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> rgb(size_t{side} * side * 3);
  if (!png_image_finish_read(&png.image, nullptr, rgb.data(), 0, nullptr)) {
    return Corrupt(std::string("color PNG fails to decode: ") + png.image.message);
  }
  return rgb;
}

StatusOr<std::vector<uint8_t>> EncodeJpeg(std::span<const uint8_t> rgb, uint32_t side, int quality) {
  TjHandle tj(tjInitCompress());
  if (!tj) return Internal("TurboJPEG cannot start a compressor");
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  const int s = static_cast<int>(side);
  if (tjCompress2(tj.get(), rgb.data(), s, 0, s, TJPF_RGB, &jpeg, &size, TJSAMP_420, quality, TJFLAG_ACCURATEDCT) != 0) {
    if (jpeg) tjFree(jpeg);
    return Internal(std::string("TurboJPEG: ") + tjGetErrorStr2(tj.get()));
  }
  std::vector<uint8_t> out(jpeg, jpeg + size);
  tjFree(jpeg);
  return out;
}

StatusOr<std::vector<uint8_t>> DecodeJpeg(std::span<const uint8_t> image, uint32_t side) {
  TjHandle tj(tjInitDecompress());
  if (!tj) return Internal("TurboJPEG cannot start a decompressor");
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  if (tjDecompressHeader3(tj.get(), image.data(), image.size(), &width, &height, &subsampling, &colorspace) != 0) {
    return Corrupt(std::string("color JPEG: ") + tjGetErrorStr2(tj.get()));
  }
  if (width != static_cast<int>(side) || height != static_cast<int>(side)) return Corrupt("color image has the wrong size");
  std::vector<uint8_t> rgb(size_t{side} * side * 3);
  // A corrupt scan is an error, not a warning with garbage texels.
  if (tjDecompress2(tj.get(), image.data(), image.size(), rgb.data(), width, 0, height, TJPF_RGB, TJFLAG_STOPONWARNING) != 0) {
    return Corrupt(std::string("color JPEG fails to decode: ") + tjGetErrorStr2(tj.get()));
  }
  return rgb;
}

StatusOr<std::vector<uint8_t>> EncodeWebp(std::span<const uint8_t> rgb, uint32_t side, int quality) {
  WebPConfig config;
  WebPPicture picture;
  if (!WebPConfigInit(&config) || !WebPPictureInit(&picture)) return Internal("libwebp version mismatch");
  config.quality = static_cast<float>(quality);
  config.method = 6;
  picture.width = static_cast<int>(side);
  picture.height = static_cast<int>(side);
  WebPMemoryWriter writer;
  WebPMemoryWriterInit(&writer);
  picture.writer = WebPMemoryWrite;
  picture.custom_ptr = &writer;
  const bool ok = WebPPictureImportRGB(&picture, rgb.data(), static_cast<int>(side) * 3) && WebPEncode(&config, &picture);
  const int error = picture.error_code;
  WebPPictureFree(&picture);
  std::vector<uint8_t> out;
  if (ok) out.assign(writer.mem, writer.mem + writer.size);
  WebPMemoryWriterClear(&writer);
  if (!ok) return Internal("libwebp failed to encode the color image (error " + std::to_string(error) + ")");
  return out;
}

StatusOr<std::vector<uint8_t>> DecodeWebp(std::span<const uint8_t> image, uint32_t side) {
  int width = 0, height = 0;
  if (!WebPGetInfo(image.data(), image.size(), &width, &height)) return Corrupt("color image is not a valid WebP file");
  if (width != static_cast<int>(side) || height != static_cast<int>(side)) return Corrupt("color image has the wrong size");
  std::vector<uint8_t> rgb(size_t{side} * side * 3);
  if (!WebPDecodeRGBInto(image.data(), image.size(), rgb.data(), rgb.size(), static_cast<int>(side) * 3)) {
    return Corrupt("color WebP fails to decode");
  }
  return rgb;
}

}  // namespace

const char* ImageFormatName(ImageFormat format) {
  switch (format) {
    case ImageFormat::kPng: return "png";
    case ImageFormat::kJpeg: return "jpeg";
    case ImageFormat::kWebp: return "webp";
  }
  return "?";
}

StatusOr<std::vector<uint8_t>> EncodeImageFile(std::span<const uint8_t> rgb, uint32_t side, ImageFormat format,
                                               int quality) {
  if (rgb.size() != size_t{side} * side * 3) return InvalidArgument("texture size does not match its side");
  switch (format) {
    case ImageFormat::kPng: return EncodePng(rgb, side);
    case ImageFormat::kJpeg: return EncodeJpeg(rgb, side, quality);
    case ImageFormat::kWebp: return EncodeWebp(rgb, side, quality);
  }
  return InvalidArgument("unknown image format");
}

StatusOr<std::vector<uint8_t>> DecodeImageFile(std::span<const uint8_t> image, ImageFormat format, uint32_t side) {
  switch (format) {
    case ImageFormat::kPng: return DecodePng(image, side);
    case ImageFormat::kJpeg: return DecodeJpeg(image, side);
    case ImageFormat::kWebp: return DecodeWebp(image, side);
  }
  return Corrupt("unknown image format");
}

}  // namespace pointdag

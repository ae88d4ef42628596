#pragma once
/// Image files: PNG (8 / 16 bit, libpng), float32 OpenEXR, NumPy .npy. Images are row-major,
/// row 0 at the top, channels interleaved.
#include <cstdint>
#include <string>
#include <vector>

namespace papersim::scenegen {

/// An image of floats (row-major, interleaved channels).
struct ImageF {
  int width = 0, height = 0, channels = 0;
  std::vector<float> data;
  ImageF() = default;
  ImageF(int w, int h, int c)
      : width(w), height(h), channels(c), data(std::size_t(w) * h * c, 0.0f) {}
  float& at(int x, int y, int c) { return data[(std::size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c) const { return data[(std::size_t(y) * width + x) * channels + c]; }
};

/// Read a PNG, values scaled to [0, 1] as stored (no gamma decoding); grey, grey+alpha, RGB,
/// RGBA; 8 or 16 bits. @throw IoError when unreadable or not a PNG.
ImageF read_png(const std::string& path);
/// Raw 16-bit samples of a PNG (exact integers). @throw IoError
std::vector<std::uint16_t> read_png16(const std::string& path, int& width, int& height,
                                      int& channels);
/// Write a PNG with 1, 3 or 4 channels, values in [0, 1] quantised by rounding.
/// @param bits 8 or 16. @throw common::OutputError
void write_png(const std::string& path, const ImageF& image, int bits);
/// Write a float32 OpenEXR (ZIP compression) with the given channel names.
/// @throw common::OutputError (also when the file reads back incomplete)
void write_exr(const std::string& path, const ImageF& image, const std::vector<std::string>& names);
/// Read the named channels of a float OpenEXR. @throw IoError
ImageF read_exr(const std::string& path, const std::vector<std::string>& names);
/// Write a float32 little-endian .npy of shape (height, width, channels). @throw
/// common::OutputError
void write_npy(const std::string& path, const ImageF& image);

/// sRGB transfer functions.
double srgb_to_linear(double v);
double linear_to_srgb(double v);

/// True when the file starts with the PNG or JPEG signature.
bool is_png_file(const std::string& path);
bool is_jpeg_file(const std::string& path);

}  // namespace papersim::scenegen

#include "scenegen/image_io.hpp"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

#include "common/atomic_file.hpp"
#include "scenegen/errors.hpp"

namespace papersim::scenegen {
namespace {

// libpng reports through longjmp; its default handler would also print to stderr.
void png_error_quiet(png_structp png, png_const_charp) { png_longjmp(png, 1); }
void png_warning_quiet(png_structp, png_const_charp) {}

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};

bool starts_with(const std::string& path, const unsigned char* sig, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> buf(n);
  if (!in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n))) return false;
  return std::memcmp(buf.data(), sig, n) == 0;
}

// libpng reports errors by longjmp to the last setjmp. A longjmp must not cross a frame that
// holds C++ objects with destructors (it skips them: a leak at best), so every libpng call that
// can fail runs in one of these small functions, which hold none: each sets its own jump point
// and returns false when libpng failed, and the caller (which owns the buffers) cleans up.

/// png_read_info up to png_read_update_info, with the transformations decode wants.
bool png_read_header(png_structp png, png_infop info, FILE* fp) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, fp);
  png_read_info(png, info);
  png_set_expand(png);  // palette -> RGB, low-bit grey -> 8 bit, tRNS -> alpha
  png_set_swap(png);    // 16-bit samples in host (little-endian) order
  png_read_update_info(png, info);
  return true;
}

bool png_read_rows(png_structp png, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  return true;
}

/// png_init_io, the header and png_write_info.
bool png_write_header(png_structp png, png_infop info, FILE* fp, int width, int height, int bits,
                      int type) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, fp);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bits,
               type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // zlib's fastest level: a whole sample writes four full-size PNGs, and the default level
  // costs about three times the CPU for files ~10% smaller.
  png_set_compression_level(png, 1);
  png_write_info(png, info);
  return true;
}

bool png_write_one_row(png_structp png, png_const_bytep row) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_write_row(png, row);
  return true;
}

bool png_write_finish(png_structp png) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_write_end(png, nullptr);
  return true;
}

/// Decode a PNG into 16-bit samples (8-bit samples are widened by x257).
std::vector<std::uint16_t> decode(const std::string& path, int& w, int& h, int& c, int& bits) {
  std::unique_ptr<FILE, FileCloser> fp(std::fopen(path.c_str(), "rb"));
  if (!fp) throw IoError("cannot open image '" + path + "'");
  if (!is_png_file(path)) throw IoError("'" + path + "' is not a PNG file");
  png_structp png =
      png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, png_error_quiet, png_warning_quiet);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  const auto fail = [&] {
    png_destroy_read_struct(&png, &info, nullptr);
    return IoError("cannot decode PNG '" + path + "'");
  };
  if (!png || !info || !png_read_header(png, info, fp.get())) throw fail();
  w = static_cast<int>(png_get_image_width(png, info));
  h = static_cast<int>(png_get_image_height(png, info));
  c = png_get_channels(png, info);
  bits = png_get_bit_depth(png, info);
  const std::size_t rowbytes = png_get_rowbytes(png, info);
  std::vector<unsigned char> buf(rowbytes * h);
  std::vector<png_bytep> rows(h);
  for (int y = 0; y < h; ++y) rows[y] = buf.data() + rowbytes * y;
  if (!png_read_rows(png, rows.data())) throw fail();
  png_destroy_read_struct(&png, &info, nullptr);
  std::vector<std::uint16_t> out(std::size_t(w) * h * c);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (bits == 16) {
      std::uint16_t v;
      std::memcpy(&v, buf.data() + 2 * i, 2);
      out[i] = v;
    } else {
      out[i] = static_cast<std::uint16_t>(buf[i] * 257);
    }
  }
  return out;
}

}  // namespace

bool is_png_file(const std::string& path) {
  static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  return starts_with(path, sig, 8);
}

bool is_jpeg_file(const std::string& path) {
  static const unsigned char sig[3] = {0xFF, 0xD8, 0xFF};
  return starts_with(path, sig, 3);
}

std::vector<std::uint16_t> read_png16(const std::string& path, int& w, int& h, int& c) {
  int bits = 0;
  return decode(path, w, h, c, bits);
}

ImageF read_png(const std::string& path) {
  int w = 0, h = 0, c = 0, bits = 0;
  const auto raw = decode(path, w, h, c, bits);
  ImageF img(w, h, c);
  for (std::size_t i = 0; i < raw.size(); ++i) img.data[i] = raw[i] / 65535.0f;
  return img;
}

void write_png(const std::string& path, const ImageF& image, int bits) {
  std::unique_ptr<FILE, FileCloser> fp(std::fopen(path.c_str(), "wb"));
  if (!fp) throw common::OutputError("cannot write image '" + path + "'");
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, png_error_quiet, png_warning_quiet);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  const auto fail = [&] {
    png_destroy_write_struct(&png, &info);
    return common::OutputError("cannot write PNG '" + path + "'");
  };
  const int type = image.channels == 1   ? PNG_COLOR_TYPE_GRAY
                   : image.channels == 3 ? PNG_COLOR_TYPE_RGB
                                         : PNG_COLOR_TYPE_RGBA;
  if (!png || !info ||
      !png_write_header(png, info, fp.get(), image.width, image.height, bits, type))
    throw fail();
  const int bytes = bits / 8;
  const double maxv = bits == 16 ? 65535.0 : 255.0;
  std::vector<unsigned char> row(std::size_t(image.width) * image.channels * bytes);
  for (int y = 0; y < image.height; ++y) {
    for (int i = 0; i < image.width * image.channels; ++i) {
      const double v = std::clamp(
          static_cast<double>(image.data[std::size_t(y) * image.width * image.channels + i]), 0.0,
          1.0);
      const auto q = static_cast<unsigned>(std::lround(v * maxv));
      if (bytes == 2) {
        row[2 * i] = static_cast<unsigned char>(q >> 8);  // PNG is big-endian
        row[2 * i + 1] = static_cast<unsigned char>(q & 0xFF);
      } else {
        row[i] = static_cast<unsigned char>(q);
      }
    }
    if (!png_write_one_row(png, row.data())) throw fail();
  }
  if (!png_write_finish(png)) throw fail();
  png_destroy_write_struct(&png, &info);
  // fclose writes what the buffer still holds: a full disk shows there at the latest.
  const bool flushed = std::fflush(fp.get()) == 0;
  if (std::fclose(fp.release()) != 0 || !flushed)
    throw common::OutputError("cannot write image '" + path + "'");
}

void write_exr(const std::string& path, const ImageF& image,
               const std::vector<std::string>& names) {
  try {
    Imf::Header header(image.width, image.height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const auto& n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer fb;
    const std::size_t xs = sizeof(float) * image.channels, ys = xs * image.width;
    for (std::size_t c = 0; c < names.size(); ++c)
      fb.insert(names[c], Imf::Slice(Imf::FLOAT, (char*)(image.data.data() + c), xs, ys));
    file.setFrameBuffer(fb);
    file.writePixels(image.height);
  } catch (const std::exception& e) {
    throw common::OutputError("cannot write EXR '" + path + "': " + e.what());
  }
  // The line offset table is written when the file closes, where errors are not reported:
  // read the file back.
  bool complete = false;
  try {
    complete = Imf::InputFile(path.c_str()).isComplete();
  } catch (const std::exception&) {
  }
  if (!complete)
    throw common::OutputError("cannot write EXR '" + path + "' (incomplete file; full disk?)");
}

ImageF read_exr(const std::string& path, const std::vector<std::string>& names) {
  try {
    Imf::InputFile file(path.c_str());
    const auto dw = file.header().dataWindow();
    ImageF img(dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1, static_cast<int>(names.size()));
    Imf::FrameBuffer fb;
    const std::size_t xs = sizeof(float) * img.channels, ys = xs * img.width;
    for (std::size_t c = 0; c < names.size(); ++c)
      fb.insert(names[c],
                Imf::Slice(Imf::FLOAT,
                           (char*)(img.data.data() + c) - (dw.min.x * xs + dw.min.y * ys), xs, ys));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return img;
  } catch (const std::exception& e) {
    throw IoError("cannot read EXR '" + path + "': " + e.what());
  }
}

void write_npy(const std::string& path, const ImageF& image) {
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                       std::to_string(image.height) + ", " + std::to_string(image.width) + ", " +
                       std::to_string(image.channels) + "), }";
  const std::size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header += '\n';
  const auto len = static_cast<std::uint16_t>(header.size());
  common::write_file_atomically(path, [&](std::ostream& out) {
    out.write("\x93NUMPY\x01\x00", 8);
    out.put(static_cast<char>(len & 0xFF));
    out.put(static_cast<char>(len >> 8));
    out << header;
    out.write(reinterpret_cast<const char*>(image.data.data()),
              static_cast<std::streamsize>(image.data.size() * sizeof(float)));
  });
}

double srgb_to_linear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}
double linear_to_srgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

}  // namespace papersim::scenegen

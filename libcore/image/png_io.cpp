#include "image/png_io.h"

#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <new>

#include "base/error.h"
#include "image/codec.h"

namespace mvtm {

namespace {

// Filled inside libpng's C frames, so no allocation (an exception there would cross C code).
struct PngErrors {
  char message[256] = "";
};

void OnError(png_structp png, png_const_charp msg) {
  auto* e = static_cast<PngErrors*>(png_get_error_ptr(png));
  std::snprintf(e->message, sizeof e->message, "%s", msg ? msg : "unknown libpng error");
  png_longjmp(png, 1);
}

void OnWarning(png_structp, png_const_charp) {}  // recoverable; never printed

// Ancillary chunks mvtm never reads (text, ICC profile, Exif, palettes, calibration), each a
// 4-byte name and a NUL as png_set_keep_unknown_chunks wants them.
const png_byte kSkippedChunks[] = "tEXt\0zTXt\0iTXt\0iCCP\0eXIf\0sPLT\0pCAL\0sCAL";

struct File {
  FILE* f = nullptr;
  ~File() {
    if (f) std::fclose(f);
  }
};

struct ReadStruct {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~ReadStruct() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

struct Header {
  png_uint_32 w = 0, h = 0;
  int channels = 0, bits = 8;
};

// After png_read_info: the transforms that give OpenImageIO's pixels, and the output layout.
// Plain C calls only (libpng may longjmp out of it).
void SetTransforms(png_structp png, png_infop info, Header* out) {
  int depth = 0, colour = 0, interlace = 0;
  png_get_IHDR(png, info, &out->w, &out->h, &depth, &colour, &interlace, nullptr, nullptr);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->channels = png_get_channels(png, info);
  out->bits = png_get_bit_depth(png, info) == 16 ? 16 : 8;
}

[[noreturn]] void Fail(const std::string& path, const PngErrors& e) {
  throw Error(path, 0,
              "cannot read image: " + std::string(e.message[0] ? e.message : "corrupt PNG"));
}

}  // namespace

bool IsPngFile(const std::string& path) {
  File f;
  f.f = std::fopen(path.c_str(), "rb");
  unsigned char sig[8];
  return f.f && std::fread(sig, 1, 8, f.f) == 8 && png_sig_cmp(sig, 0, 8) == 0;
}

Image ReadPng(const std::string& path, bool header_only) {
  File f;
  f.f = std::fopen(path.c_str(), "rb");
  if (!f.f) throw Error(path, 0, "cannot open");
  std::error_code ec;
  const uint64_t file_size = std::filesystem::file_size(path, ec);
  if (ec) throw Error(path, 0, "cannot open: " + ec.message());
  PngErrors errors;
  ReadStruct rs;
  rs.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &errors, OnError, OnWarning);
  if (rs.png) rs.info = png_create_info_struct(rs.png);
  if (!rs.png || !rs.info) throw Error(path, 0, "cannot read image: out of memory");
  // Objects that outlive a longjmp live in this frame, are created before setjmp and are not
  // changed between setjmp and longjmp except through pointers (and `ok`, volatile).
  Header hdr;
  volatile bool ok = false;
  if (setjmp(png_jmpbuf(rs.png)) == 0) {
    png_init_io(rs.png, f.f);
    png_set_user_limits(rs.png, kMaxReadImageSide, kMaxReadImageSide);
    // libpng allocates what an ancillary chunk's length claims before reading it (fuzzing: an
    // 877-byte file whose tEXt chunk claims 1.9 GB). mvtm reads none of the text, profile or
    // Exif chunks, so they are skipped unread, and no other chunk may claim more than the file.
    png_set_keep_unknown_chunks(rs.png, PNG_HANDLE_CHUNK_NEVER, kSkippedChunks,
                                int(sizeof kSkippedChunks / 5));
    png_set_chunk_malloc_max(rs.png, std::max<png_alloc_size_t>(file_size, 1));
    png_read_info(rs.png, rs.info);
    SetTransforms(rs.png, rs.info, &hdr);
    ok = true;
  }
  if (!ok) Fail(path, errors);
  if (hdr.w == 0 || hdr.h == 0 || uint64_t(hdr.w) * hdr.h > kMaxImagePixels)
    throw Error(path, 0,
                "image claims " + std::to_string(hdr.w) + "x" + std::to_string(hdr.h) +
                    ", beyond mvtm's limits (65536 pixels a side, 2^30 pixels)");
  if (header_only) {
    Image spec;
    spec.width = int(hdr.w), spec.height = int(hdr.h), spec.channels = hdr.channels;
    spec.bits = hdr.bits;
    return spec;
  }
  // Deflate expands at most 1032:1, so a file smaller than that share of its pixel rows is cut
  // short: refused before the (possibly huge) allocation.
  const double raw = double(png_get_rowbytes(rs.png, rs.info)) * hdr.h;
  CheckHeaderFitsFile(path, hdr.w, hdr.h, raw, 1032.0, 65536);
  Image img(int(hdr.w), int(hdr.h), hdr.channels, hdr.bits);
  const size_t rowbytes = png_get_rowbytes(rs.png, rs.info);
  std::vector<unsigned char> buf(rowbytes * hdr.h);
  std::vector<png_bytep> rows(hdr.h);
  for (png_uint_32 y = 0; y < hdr.h; ++y) rows[y] = buf.data() + rowbytes * y;
  ok = false;
  if (setjmp(png_jmpbuf(rs.png)) == 0) {
    png_read_image(rs.png, rows.data());
    png_read_end(rs.png, nullptr);
    ok = true;
  }
  if (!ok) Fail(path, errors);
  if (hdr.bits == 16) {  // PNG stores big-endian samples
    for (size_t i = 0; i < img.data.size(); ++i)
      img.data[i] = float((unsigned(buf[2 * i]) << 8) | buf[2 * i + 1]);
  } else {
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = buf[i];
  }
  return img;
}

namespace {
struct WriteStruct {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~WriteStruct() { png_destroy_write_struct(&png, info ? &info : nullptr); }
};

void AppendBytes(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::vector<unsigned char>*>(png_get_io_ptr(png));
  bool grown = true;
  try {  // no exception may cross libpng's C frames
    out->insert(out->end(), data, data + n);
  } catch (const std::bad_alloc&) {
    grown = false;
  }
  if (!grown) png_error(png, "out of memory");
}
void Flush(png_structp) {}

// Plain C calls only (libpng may longjmp out of it).
void WritePngRows(png_structp png, png_infop info, png_uint_32 w, png_uint_32 h, int bits,
                  int colour, int mode, png_bytepp rows) {
  const bool fast = mode != int(PngCompression::kDefault);
  png_set_compression_level(png, fast ? 1 : 6);
  png_set_compression_strategy(png, fast ? Z_RLE : Z_DEFAULT_STRATEGY);
  if (mode == int(PngCompression::kFastFlat))
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
  png_set_IHDR(png, info, w, h, bits, colour, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  png_set_oFFs(png, info, 0, 0, PNG_OFFSET_PIXEL);
  png_time epoch{};
  epoch.year = 1970, epoch.month = 1, epoch.day = 1;
  png_set_tIME(png, info, &epoch);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
}
}  // namespace

std::vector<unsigned char> EncodePng(const std::string& path, const Image& img,
                                     PngCompression compression) {
  if (img.bits != 8 && img.bits != 16)
    throw Error(path, 0, "PNG holds 8 or 16 bits per sample, not " + std::to_string(img.bits));
  if (img.channels < 1 || img.channels > 4)
    throw Error(path, 0, "PNG holds 1 to 4 channels, not " + std::to_string(img.channels));
  static constexpr int kColour[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                    PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  const size_t bytes_per_sample = img.bits / 8;
  const size_t rowbytes = size_t(img.width) * img.channels * bytes_per_sample;
  std::vector<unsigned char> buf(rowbytes * img.height);
  const double maxv = img.MaxValue();
  for (size_t i = 0; i < img.data.size(); ++i) {
    const auto v = unsigned(std::clamp(std::nearbyint(double(img.data[i])), 0.0, maxv));
    if (bytes_per_sample == 2) {  // big-endian samples
      buf[2 * i] = (unsigned char)(v >> 8);
      buf[2 * i + 1] = (unsigned char)(v & 0xff);
    } else {
      buf[i] = (unsigned char)v;
    }
  }
  std::vector<png_bytep> rows(img.height);
  for (int y = 0; y < img.height; ++y) rows[y] = buf.data() + rowbytes * y;

  std::vector<unsigned char> out;
  out.reserve(buf.size() / 2 + 1024);
  PngErrors errors;
  WriteStruct ws;
  ws.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, OnError, OnWarning);
  if (ws.png) ws.info = png_create_info_struct(ws.png);
  if (!ws.png || !ws.info) throw Error(path, 0, "cannot encode image: out of memory");
  volatile bool ok = false;
  if (setjmp(png_jmpbuf(ws.png)) == 0) {
    png_set_write_fn(ws.png, &out, AppendBytes, Flush);
    WritePngRows(ws.png, ws.info, png_uint_32(img.width), png_uint_32(img.height), img.bits,
                 kColour[img.channels - 1], int(compression), rows.data());
    ok = true;
  }
  if (!ok)
    throw Error(path, 0,
                "cannot encode image: " + std::string(errors.message[0] ? errors.message : "?"));
  return out;
}

}  // namespace mvtm

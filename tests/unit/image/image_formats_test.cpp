// The image layer's own codecs (libpng, OpenEXR, libjpeg-turbo) against a peer: OpenImageIO,
// through which mvtm read and wrote every image before. Writes must be byte-identical to what
// OpenImageIO wrote with mvtm's settings; reads must give OpenImageIO's pixels; every format
// must round-trip both ways (mvtm writes, OpenImageIO reads, and the reverse), including the
// formats that go through the dlopen'd plugin.
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <unistd.h>

// jpeglib.h needs size_t and FILE declared first.
#include <cstddef>
#include <cstdio>
// clang-format off
#include <jpeglib.h>
// clang-format on

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "base/error.h"
#include "image/exr_io.h"
#include "image/image.h"
#include "image/jpeg_io.h"
#include "image/png_io.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;
namespace OIIO = OIIO_NAMESPACE;

// One scratch folder for the whole test program, removed at exit.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("mvtm_formats_" + std::to_string(::getpid()));
  Scratch() { fs::create_directories(dir); }
  ~Scratch() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
} scratch;
const fs::path& Dir() { return scratch.dir; }

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Smooth gradients plus noise (so zlib and the PNG filters have real work), values in range.
Image Pattern(int w, int h, int c, int bits, unsigned seed) {
  std::mt19937 rng(seed);
  Image img(w, h, c, bits);
  const double maxv = bits == 32 ? 1.0 : img.MaxValue();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k) {
        double v =
            0.5 + 0.4 * std::sin(0.05 * x * (k + 1) + 0.07 * y) + 0.05 * (rng() % 100) / 100.0;
        v = std::clamp(v, 0.0, 1.0) * maxv;
        img.at(x, y, k) = bits == 32 ? float(v * 37.5 - 3) : float(std::round(v));
      }
  return img;
}

// Samples in the image's own type (mvtm's floats hold 0..255 / 0..65535 for 8/16 bits).
bool WriteNative(OIIO::ImageOutput& o, const Image& img) {
  if (img.bits == 32) return o.write_image(OIIO::TypeDesc::FLOAT, img.data.data());
  if (img.bits == 16) {
    std::vector<uint16_t> v(img.data.begin(), img.data.end());
    return o.write_image(OIIO::TypeDesc::UINT16, v.data());
  }
  std::vector<uint8_t> v(img.data.begin(), img.data.end());
  return o.write_image(OIIO::TypeDesc::UINT8, v.data());
}

// What OpenImageIO wrote for mvtm: the settings of mvtm's former WriteImage.
std::string OiioBytes(const fs::path& path, const Image& img) {
  auto o = OIIO::ImageOutput::create(path.string());
  OIIO::TypeDesc type = img.bits == 8    ? OIIO::TypeDesc::UINT8
                        : img.bits == 16 ? OIIO::TypeDesc::UINT16
                                         : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(img.width, img.height, img.channels, type);
  if (img.bits == 32) spec.attribute("compression", "zip");
  spec.attribute("oiio:UnassociatedAlpha", 1);
  spec.attribute("DateTime", "1970:01:01 00:00:00");
  EXPECT_TRUE(o->open(path.string(), spec));
  EXPECT_TRUE(WriteNative(*o, img));
  EXPECT_TRUE(o->close());
  return Slurp(path);
}

// OpenImageIO's reading (unassociated alpha), as mvtm read before.
Image OiioRead(const fs::path& path) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path.string(), &config);
  EXPECT_TRUE(in) << OIIO::geterror();
  if (!in) return {};
  const auto& s = in->spec();
  const int bits = s.format == OIIO::TypeDesc::UINT8    ? 8
                   : s.format == OIIO::TypeDesc::UINT16 ? 16
                                                        : 32;
  Image img(s.width, s.height, s.nchannels, bits);
  if (bits == 32) {
    EXPECT_TRUE(in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, img.data.data()));
  } else if (bits == 16) {
    std::vector<uint16_t> v(img.data.size());
    EXPECT_TRUE(in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::UINT16, v.data()));
    std::copy(v.begin(), v.end(), img.data.begin());
  } else {
    std::vector<uint8_t> v(img.data.size());
    EXPECT_TRUE(in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::UINT8, v.data()));
    std::copy(v.begin(), v.end(), img.data.begin());
  }
  return img;
}

void ExpectSamePixels(const Image& a, const Image& b, const std::string& what) {
  ASSERT_EQ(a.width, b.width) << what;
  ASSERT_EQ(a.height, b.height) << what;
  ASSERT_EQ(a.channels, b.channels) << what;
  EXPECT_EQ(a.bits, b.bits) << what;
  size_t differ = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    const float x = a.data[i], y = b.data[i];
    if (!(x == y || (std::isnan(x) && std::isnan(y)))) ++differ;
  }
  EXPECT_EQ(differ, 0u) << what << ": samples that differ";
}

// `encoded` (the codec's bytes) and the public writer's file (atomic) are the bytes OpenImageIO
// wrote for `img`, and both readers read `img` back from the file.
void ExpectWrittenLikeOpenImageIO(const std::string& ext, const Image& img,
                                  const std::vector<unsigned char>& encoded,
                                  const std::string& what) {
  const std::string want = OiioBytes(Dir() / ("oiio." + ext), img);
  EXPECT_TRUE(want == std::string(encoded.begin(), encoded.end())) << what;
  const fs::path mine = Dir() / ("mvtm." + ext);
  WriteImage(mine.string(), img);
  EXPECT_TRUE(Slurp(mine) == want) << what;
  ExpectSamePixels(ReadImage(mine.string()), img, what);
  ExpectSamePixels(OiioRead(mine), img, what);
}

TEST(ImageFormats, PngBytesAreOpenImageIOs) {
  for (int bits : {8, 16})
    for (int c = 1; c <= 4; ++c)
      for (auto [w, h] : {std::pair{7, 3}, std::pair{80, 24}, std::pair{1241, 376}}) {
        const Image img = Pattern(w, h, c, bits, unsigned(w + c + bits));
        const std::string what = std::to_string(w) + "x" + std::to_string(h) + "x" +
                                 std::to_string(c) + " " + std::to_string(bits) + "-bit PNG";
        ExpectWrittenLikeOpenImageIO("png", img, EncodePng("x.png", img), what);
      }
}

// The fast settings (masks): other bytes, the same pixels for both readers, and for a mask about
// the size of the default settings.
TEST(ImageFormats, FastPngKeepsThePixels) {
  for (int bits : {8, 16})
    for (int c = 1; c <= 4; ++c) {
      const Image img = Pattern(203, 61, c, bits, unsigned(c * bits));
      const std::string what = std::to_string(c) + "x" + std::to_string(bits) + " fast PNG";
      for (auto mode : {PngCompression::kFast, PngCompression::kFastFlat}) {
        WriteImage((Dir() / "fast.png").string(), img, mode);
        ExpectSamePixels(ReadImage((Dir() / "fast.png").string()), img, what);
        ExpectSamePixels(OiioRead(Dir() / "fast.png"), img, what);
      }
    }
  Image mask(1241, 376, 1, 8);
  for (int y = 100; y < 220; ++y)
    for (int x = 300; x < 520; ++x) mask.at(x, y) = 255;
  const auto fast = EncodePng("m.png", mask, PngCompression::kFastFlat);
  const auto dflt = EncodePng("m.png", mask);
  EXPECT_LT(fast.size(), 3 * dflt.size());
}

TEST(ImageFormats, ExrBytesAreOpenImageIOs) {
  for (int c = 1; c <= 4; ++c)
    for (auto [w, h] : {std::pair{5, 2}, std::pair{80, 24}, std::pair{1241, 376}}) {
      Image img = Pattern(w, h, c, 32, unsigned(w * c));
      img.data[0] = std::numeric_limits<float>::infinity();  // depth maps hold +inf (no hit)
      img.data[img.data.size() / 2] = -0.f;
      const std::string what =
          std::to_string(w) + "x" + std::to_string(h) + "x" + std::to_string(c) + " EXR";
      ExpectWrittenLikeOpenImageIO("exr", img, EncodeExr("x.exr", img), what);
    }
}

// EXR files mvtm did not write: half channels, tiles, a data window away from the origin, other
// compressions; all read natively with OpenImageIO's pixels. Multi-part files, UINT channels
// and other channel sets go to the plugin and still read as OpenImageIO reads them.
TEST(ImageFormats, ExrReadsLikeOpenImageIO) {
  struct Case {
    std::string name;
    int c;
    OIIO::TypeDesc type;
    std::string compression;
    int tile, x0, y0;
    bool native;
    std::vector<std::string> names;
  };
  const std::vector<Case> cases = {
      {"half_rgb", 3, OIIO::TypeDesc::HALF, "piz", 0, 0, 0, true, {}},
      {"half_y_tiled", 1, OIIO::TypeDesc::HALF, "zip", 16, 0, 0, true, {}},
      {"float_rgba_tiled_rle", 4, OIIO::TypeDesc::FLOAT, "rle", 32, 0, 0, true, {}},
      {"float_window", 2, OIIO::TypeDesc::FLOAT, "none", 0, 13, -7, true, {}},
      {"float_z", 1, OIIO::TypeDesc::FLOAT, "zips", 0, 0, 0, true, {"Z"}},
      {"uint_y", 1, OIIO::TypeDesc::UINT, "zip", 0, 0, 0, false, {}},
      {"float_xyz", 3, OIIO::TypeDesc::FLOAT, "zip", 0, 0, 0, false, {"X", "Y", "Z"}},
  };
  for (const auto& k : cases) {
    const fs::path p = Dir() / (k.name + ".exr");
    Image src = Pattern(61, 29, k.c, 32, 7);
    if (k.type == OIIO::TypeDesc::UINT)
      for (float& v : src.data) v = std::round(v * 1000 + 5000);
    OIIO::ImageSpec spec(61, 29, k.c, k.type);
    spec.x = k.x0, spec.y = k.y0;
    spec.attribute("compression", k.compression);
    if (k.tile) spec.tile_width = spec.tile_height = k.tile;
    if (!k.names.empty()) spec.channelnames = k.names;
    auto o = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(o->open(p.string(), spec)) << o->geterror();
    ASSERT_TRUE(o->write_image(OIIO::TypeDesc::FLOAT, src.data.data()));
    ASSERT_TRUE(o->close());
    Image native;
    EXPECT_EQ(ReadExr(p.string(), false, &native), k.native) << k.name;
    const Image want = OiioRead(p);
    ExpectSamePixels(ReadImage(p.string()), want, k.name);
    const ImageSpecInfo info = ReadImageSpec(p.string());
    EXPECT_EQ(info.width, want.width) << k.name;
    EXPECT_EQ(info.channels, want.channels) << k.name;
  }
}

TEST(ImageFormats, JpegReadsLikeOpenImageIO) {
  struct Case {
    std::string name;
    int c;
    std::string subsampling;
    bool progressive;
  };
  for (const Case& k :
       {Case{"grey", 1, "", false}, Case{"420", 3, "4:2:0", false}, Case{"422", 3, "4:2:2", false},
        Case{"444", 3, "4:4:4", false}, Case{"420_progressive", 3, "4:2:0", true}}) {
    for (auto [w, h] : {std::pair{1241, 376}, std::pair{33, 17}}) {
      const fs::path p = Dir() / (k.name + ".jpg");
      const Image src = Pattern(w, h, k.c, 8, 3);
      OIIO::ImageSpec spec(w, h, k.c, OIIO::TypeDesc::UINT8);
      spec.attribute("Compression", "jpeg:85");
      if (!k.subsampling.empty()) spec.attribute("jpeg:subsampling", k.subsampling);
      if (k.progressive) spec.attribute("jpeg:progressive", 1);
      auto o = OIIO::ImageOutput::create(p.string());
      ASSERT_TRUE(o->open(p.string(), spec));
      ASSERT_TRUE(WriteNative(*o, src));
      ASSERT_TRUE(o->close());
      Image native;
      ASSERT_TRUE(IsJpegFile(p.string()));
      ASSERT_TRUE(ReadJpeg(p.string(), false, &native)) << k.name;
      ExpectSamePixels(native, OiioRead(p), k.name + " " + std::to_string(w));
    }
  }
  // Cut short in the middle of the scan: an error naming the file (libjpeg alone would fill the
  // rest with grey and only warn).
  {
    const Image src = Pattern(1241, 376, 3, 8, 3);
    auto o = OIIO::ImageOutput::create((Dir() / "whole.jpg").string());
    ASSERT_TRUE(o->open((Dir() / "whole.jpg").string(),
                        OIIO::ImageSpec(1241, 376, 3, OIIO::TypeDesc::UINT8)));
    ASSERT_TRUE(WriteNative(*o, src));
    ASSERT_TRUE(o->close());
  }
  const std::string whole = Slurp(Dir() / "whole.jpg");
  std::ofstream(Dir() / "cut.jpg", std::ios::binary) << whole.substr(0, whole.size() * 3 / 5);
  try {
    ReadImage((Dir() / "cut.jpg").string());
    ADD_FAILURE() << "a truncated JPEG was read";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), (Dir() / "cut.jpg").string());
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

// Every format both ways: mvtm writes and OpenImageIO reads the same pixels; OpenImageIO writes
// and mvtm reads them. Formats beyond PNG/EXR/JPEG go through the dlopen'd plugin.
TEST(ImageFormats, EveryFormatRoundTripsBothWays) {
  struct Case {
    std::string ext;
    int c, bits;
    bool lossy;
  };
  for (const Case& k :
       {Case{"png", 3, 8, false}, Case{"png", 2, 16, false}, Case{"exr", 3, 32, false},
        Case{"jpg", 3, 8, true}, Case{"jpg", 1, 8, true}, Case{"tif", 4, 16, false},
        Case{"tif", 1, 32, false}, Case{"bmp", 3, 8, false}, Case{"pnm", 1, 8, false},
        Case{"webp", 3, 8, true}, Case{"hdr", 3, 32, true}, Case{"tga", 4, 8, false}}) {
    const std::string what = k.ext + " " + std::to_string(k.c) + "x" + std::to_string(k.bits);
    const Image src = Pattern(45, 31, k.c, k.bits, 11);
    const fs::path a = Dir() / ("mvtm." + k.ext), b = Dir() / ("oiio." + k.ext);
    WriteImage(a.string(), src);
    const Image by_oiio = OiioRead(a);
    if (!k.lossy) ExpectSamePixels(by_oiio, src, what + " written by mvtm, read by OpenImageIO");
    ExpectSamePixels(ReadImage(a.string()), by_oiio, what + " written by mvtm, read by both");
    OiioBytes(b, src);
    ExpectSamePixels(ReadImage(b.string()), OiioRead(b), what + " written by OpenImageIO");
  }
}

// Reading `p` throws one Error naming it, on one line, holding `needle`; returns its message.
std::string ExpectRefused(const fs::path& p, const std::string& needle) {
  try {
    ReadImage(p.string());
    ADD_FAILURE() << p << " was read";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.file(), p.string());
    EXPECT_NE(m.find(needle), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    return m;
  }
  return "";
}

TEST(ImageFormats, ErrorsNameTheFileOnOneLine) {
  const fs::path noise = Dir() / "noise.exr";
  std::ofstream(noise, std::ios::binary) << std::string("v/1\x01\x02\x00\x00\x00garbage", 16);
  const fs::path cut = Dir() / "cut.exr";
  const std::string whole = OiioBytes(Dir() / "whole.exr", Pattern(300, 200, 1, 32, 5));
  std::ofstream(cut, std::ios::binary) << whole.substr(0, whole.size() * 2 / 3);
  for (const fs::path& p : {noise, cut}) {
    const std::string m = ExpectRefused(p, "");
    EXPECT_EQ(m.find("Iex"), std::string::npos) << m;
    EXPECT_EQ(m.find("OpenEXR"), std::string::npos) << m;
  }
}

// A progressive JPEG of `scans` valid scans, grey (1 component) or CMYK (4): the DC of all
// components, then each AC coefficient k = 1..63 of the first in a scan of its own, first at half
// precision and refined when more scans are asked for, then one AC scan of each other component.
std::string ManyScanJpeg(const fs::path& path, int scans, int components = 1) {
  std::vector<jpeg_scan_info> script;
  script.push_back({components, {0, 1, 2, 3}, 0, 0, 0, 0});
  const int others = components - 1;
  const bool refine = scans - others > 64;
  for (int k = 1; k <= 63; ++k) script.push_back({1, {0}, k, k, 0, refine ? 1 : 0});
  for (int k = 1; refine && k <= 63 && int(script.size()) < scans - others; ++k)
    script.push_back({1, {0}, k, k, 1, 0});
  for (int c = 1; c <= others; ++c) script.push_back({1, {c}, 1, 63, 0, 0});
  jpeg_compress_struct c{};
  jpeg_error_mgr err{};
  c.err = jpeg_std_error(&err);
  jpeg_create_compress(&c);
  std::FILE* f = std::fopen(path.c_str(), "wb");
  jpeg_stdio_dest(&c, f);
  c.image_width = 16, c.image_height = 16, c.input_components = components;
  c.in_color_space = components == 4 ? JCS_CMYK : JCS_GRAYSCALE;
  jpeg_set_defaults(&c);
  c.scan_info = script.data(), c.num_scans = int(script.size());
  jpeg_start_compress(&c, TRUE);
  std::vector<unsigned char> row(size_t(16 * components));
  for (int y = 0; y < 16; ++y) {
    for (size_t x = 0; x < row.size(); ++x) row[x] = static_cast<unsigned char>(x * 13 + y * 7);
    JSAMPROW r = row.data();
    jpeg_write_scanlines(&c, &r, 1);
  }
  jpeg_finish_compress(&c);
  jpeg_destroy_compress(&c);
  std::fclose(f);
  return std::to_string(script.size());
}

// What a review of the readers found reachable from a few bytes (the fuzzer's domain): a file
// is read by the reader its extension names only; tiles larger than their image, multi-part and
// deep EXR, volumes and over a hundred JPEG scans are refused before anything is allocated.
// Each file is valid for its own library (OpenImageIO reads it).
TEST(ImageFormats, WhatOnlyForgedFilesHoldIsRefused) {
  const Image small = Pattern(16, 16, 3, 8, 4);
  // A TIFF named .jpg: OpenImageIO's TIFF reader took it when every reader was tried.
  const fs::path tif = Dir() / "tiff.tif", misnamed = Dir() / "tiff_named.jpg";
  WriteImage(tif.string(), small);
  fs::copy_file(tif, misnamed, fs::copy_options::overwrite_existing);
  ExpectSamePixels(ReadImage(tif.string()), small, "a TIFF named .tif");
  ExpectRefused(misnamed, "cannot read image");
  // 4096x4096 tiles in a 16x16 TIFF, and 2048x2048 tiles in a 16x16 EXR.
  for (const char* ext : {"tif", "exr"}) {
    const fs::path p = Dir() / (std::string("big_tiles.") + ext);
    OIIO::ImageSpec spec(16, 16, 3, OIIO::TypeDesc::FLOAT);
    spec.tile_width = spec.tile_height = std::string(ext) == "tif" ? 4096 : 2048;
    spec.attribute("compression", "zip");
    auto out = OIIO::ImageOutput::create(p.string());
    ASSERT_TRUE(out && out->open(p.string(), spec)) << OIIO::geterror();
    std::vector<float> px(16 * 16 * 3, 0.5f);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->close());
    ASSERT_TRUE(OIIO::ImageInput::open(p.string())) << "OpenImageIO reads " << p;
    ExpectRefused(p, "tiles in a 16x16 image");
  }
  // Two parts in one EXR.
  const fs::path parts = Dir() / "parts.exr";
  {
    OIIO::ImageSpec specs[2] = {OIIO::ImageSpec(8, 8, 1, OIIO::TypeDesc::FLOAT),
                                OIIO::ImageSpec(8, 8, 1, OIIO::TypeDesc::FLOAT)};
    auto out = OIIO::ImageOutput::create(parts.string());
    ASSERT_TRUE(out && out->open(parts.string(), 2, specs)) << OIIO::geterror();
    std::vector<float> px(64, 0.25f);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->open(parts.string(), specs[1], OIIO::ImageOutput::AppendSubimage));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
    ASSERT_TRUE(out->close());
  }
  ExpectRefused(parts, "multi-part");
  // A volume texture (8x8x4, 24-bit RGB) in a DDS file: read_image would write four slices
  // into one slice's buffer. Written by hand (OpenImageIO writes no volumes).
  const fs::path volume = Dir() / "volume.dds";
  {
    auto u32 = [](uint32_t v) {
      return std::string{char(v), char(v >> 8), char(v >> 16), char(v >> 24)};
    };
    std::string h = "DDS " + u32(124) + u32(0x1 | 0x2 | 0x4 | 0x1000 | 0x800000) + u32(8) + u32(8) +
                    u32(24) + u32(4) + u32(0) + std::string(44, '\0');
    h += u32(32) + u32(0x40) + u32(0) + u32(24) + u32(0xff0000) + u32(0xff00) + u32(0xff) + u32(0);
    h += u32(0x1000 | 0x8) + u32(0x200000) + u32(0) + u32(0) + u32(0);
    std::ofstream(volume, std::ios::binary) << h << std::string(8 * 8 * 4 * 3, '\x40');
  }
  auto in = OIIO::ImageInput::open(volume.string());
  ASSERT_TRUE(in) << OIIO::geterror();
  EXPECT_EQ(in->spec().depth, 4) << "OpenImageIO reads a volume";
  ExpectRefused(volume, "volume");
  // Progressive JPEGs: 64 scans read as libjpeg reads them, 126 refused.
  const fs::path ok = Dir() / "scans64.jpg", many = Dir() / "scans126.jpg";
  EXPECT_EQ(ManyScanJpeg(ok, 64), "64");
  EXPECT_EQ(ManyScanJpeg(many, 126), "126");
  ExpectSamePixels(ReadImage(ok.string()), OiioRead(ok), "a 64-scan progressive JPEG");
  ASSERT_TRUE(OIIO::ImageInput::open(many.string())) << "OpenImageIO reads the 126-scan JPEG";
  ExpectRefused(many, "more than 100 scans");
  // CMYK goes to OpenImageIO's reader, which takes in every scan inside open(): counted first.
  const fs::path cmyk_ok = Dir() / "cmyk_scans67.jpg", cmyk_many = Dir() / "cmyk_scans126.jpg";
  EXPECT_EQ(ManyScanJpeg(cmyk_ok, 67, 4), "67");
  EXPECT_EQ(ManyScanJpeg(cmyk_many, 126, 4), "126");
  EXPECT_EQ(ReadImage(cmyk_ok.string()).channels, OiioRead(cmyk_ok).channels) << "67 scans read";
  ASSERT_TRUE(OIIO::ImageInput::open(cmyk_many.string())) << "OpenImageIO reads 126 CMYK scans";
  ExpectRefused(cmyk_many, "more than 100 scans");
}

}  // namespace
}  // namespace mvtm

// libcore/image/png_io against a peer: OpenImageIO's PNG reader (with unassociated alpha, as
// mvtm used before) must give the same pixels for every PNG colour type, bit depth, palette,
// transparency chunk and interlacing; broken files must give one mvtm::Error naming the file.
#include "image/png_io.h"

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <zlib.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "base/error.h"
#include "image/image.h"

namespace mvtm {
namespace {

namespace fs = std::filesystem;
namespace OIIO = OIIO_NAMESPACE;

std::string Be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }

std::string Chunk(const std::string& type, const std::string& data) {
  std::string td = type + data;
  uLong crc = crc32(0, reinterpret_cast<const Bytef*>(td.data()), uInt(td.size()));
  return Be32(uint32_t(data.size())) + td + Be32(uint32_t(crc));
}

struct PngSpec {
  uint32_t w, h;
  int depth, colour, interlace;
  std::string extra;  // chunks between IHDR and IDAT (PLTE, tRNS)
};

// Random samples, filter type 0 per row; for interlaced files the raw stream is built per Adam7
// pass (each pass a small image of its own).
std::string MakePng(const PngSpec& s, std::mt19937& rng) {
  int samples = s.colour == 0 ? 1 : s.colour == 2 ? 3 : s.colour == 3 ? 1 : s.colour == 4 ? 2 : 4;
  auto rows = [&](uint32_t w, uint32_t h) {
    std::string raw;
    size_t rowbytes = (size_t(w) * samples * s.depth + 7) / 8;
    for (uint32_t y = 0; y < h; ++y) {
      raw.push_back(0);
      for (size_t b = 0; b < rowbytes; ++b) {
        unsigned v = rng() & 0xff;
        if (s.colour == 3) {
          // palette indices stay below 4 entries
          v = s.depth == 8 ? (v & 3) : s.depth == 4 ? (v & 0x33) : s.depth == 2 ? (v & 0xff) : v;
        }
        raw.push_back(char(v));
      }
    }
    return raw;
  };
  std::string raw;
  if (!s.interlace) {
    raw = rows(s.w, s.h);
  } else {
    const int x0[] = {0, 4, 0, 2, 0, 1, 0}, y0[] = {0, 0, 4, 0, 2, 0, 1};
    const int dx[] = {8, 8, 4, 4, 2, 2, 1}, dy[] = {8, 8, 8, 4, 4, 2, 2};
    for (int p = 0; p < 7; ++p) {
      uint32_t pw = s.w > uint32_t(x0[p]) ? (s.w - x0[p] + dx[p] - 1) / dx[p] : 0;
      uint32_t ph = s.h > uint32_t(y0[p]) ? (s.h - y0[p] + dy[p] - 1) / dy[p] : 0;
      if (pw && ph) raw += rows(pw, ph);
    }
  }
  std::vector<Bytef> z(compressBound(uLong(raw.size())));
  uLongf zn = uLongf(z.size());
  compress(z.data(), &zn, reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()));
  std::string ihdr =
      Be32(s.w) + Be32(s.h) + char(s.depth) + char(s.colour) + '\0' + '\0' + char(s.interlace);
  return std::string("\x89PNG\r\n\x1a\n", 8) + Chunk("IHDR", ihdr) + s.extra +
         Chunk("IDAT", std::string(reinterpret_cast<char*>(z.data()), zn)) + Chunk("IEND", "");
}

std::vector<float> ReadWithOiio(const std::string& path, int& channels) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  EXPECT_TRUE(in) << OIIO::geterror();
  const auto& spec = in->spec();
  channels = spec.nchannels;
  std::vector<float> px(size_t(spec.width) * spec.height * spec.nchannels);
  bool is16 = spec.format == OIIO::TypeDesc::UINT16;
  if (is16) {
    std::vector<uint16_t> b(px.size());
    in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT16, b.data());
    std::copy(b.begin(), b.end(), px.begin());
  } else {
    std::vector<uint8_t> b(px.size());
    in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, b.data());
    std::copy(b.begin(), b.end(), px.begin());
  }
  return px;
}

class PngTest : public ::testing::Test {
 protected:
  fs::path dir = fs::temp_directory_path() / ("mvtm_png_" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir); }
  void TearDown() override { fs::remove_all(dir); }
  std::string Write(const std::string& name, const std::string& bytes) {
    std::string p = (dir / name).string();
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
};

TEST_F(PngTest, SamePixelsAsOpenImageIOForEveryColourTypeAndDepth) {
  std::mt19937 rng(7);
  const std::string plte =
      Chunk("PLTE", std::string("\x0a\x14\x1e\x28\x32\x3c\x46\x50\x5a\x64\x6e\x78", 12));
  struct Variant {
    int colour;
    std::vector<int> depths;
    std::string trns;  // "" none
  };
  const std::vector<Variant> variants = {
      {0, {1, 2, 4, 8, 16}, ""},
      {0, {8}, Chunk("tRNS", std::string("\x00\x05", 2))},
      {0, {16}, Chunk("tRNS", std::string("\x01\x02", 2))},
      {2, {8, 16}, ""},
      {2, {8}, Chunk("tRNS", std::string("\x00\x01\x00\x02\x00\x03", 6))},
      {3, {1, 2, 4, 8}, ""},
      {3, {8}, Chunk("tRNS", std::string("\x80\x00", 2))},
      {4, {8, 16}, ""},
      {6, {8, 16}, ""},
  };
  int checked = 0;
  for (const auto& v : variants)
    for (int depth : v.depths)
      for (int interlace : {0, 1}) {
        std::string extra = (v.colour == 3 ? plte : "") + v.trns;
        PngSpec s{13, 7, depth, v.colour, interlace, extra};
        std::string name = "c" + std::to_string(v.colour) + "_d" + std::to_string(depth) + "_i" +
                           std::to_string(interlace) + (v.trns.empty() ? "" : "_t") + ".png";
        std::string path = Write(name, MakePng(s, rng));
        int oiio_channels = 0;
        std::vector<float> want = ReadWithOiio(path, oiio_channels);
        Image got = ReadPng(path);
        ASSERT_EQ(got.width, 13) << name;
        ASSERT_EQ(got.channels, oiio_channels) << name;
        ASSERT_EQ(got.data.size(), want.size()) << name;
        for (size_t i = 0; i < want.size(); ++i)
          ASSERT_EQ(got.data[i], want[i]) << name << " @" << i;
        Image spec = ReadPng(path, true);
        EXPECT_EQ(spec.channels, got.channels);
        EXPECT_EQ(spec.bits, got.bits);
        EXPECT_TRUE(spec.data.empty());
        ++checked;
      }
  EXPECT_EQ(checked, 38);
}

TEST_F(PngTest, BrokenFilesAreOneErrorNamingTheFile) {
  std::mt19937 rng(3);
  std::string good = MakePng({40, 30, 8, 2, 0, ""}, rng);
  auto expect_error = [&](const std::string& name, const std::string& bytes,
                          const std::string& needle) {
    std::string path = Write(name, bytes);
    try {
      ReadImage(path);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      std::string what = e.what();
      EXPECT_EQ(what.rfind(path + ": ", 0), 0u) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  };
  expect_error("truncated.png", good.substr(0, good.size() - 30), "cannot read image");
  std::string crc = good;
  crc[good.size() - 20] ^= 0x55;  // inside IDAT: CRC mismatch
  expect_error("crc.png", crc, "cannot read image");
  // A 10^6 x 10^6 header in 58 bytes: refused before any allocation.
  auto header_only = [](uint32_t w, uint32_t h) {
    std::string ihdr = Be32(w) + Be32(h) + std::string("\x08\x00\x00\x00\x00", 5);
    return std::string("\x89PNG\r\n\x1a\n", 8) + Chunk("IHDR", ihdr) + Chunk("IDAT", "") +
           Chunk("IEND", "");
  };
  expect_error("huge.png", header_only(1000000, 1000000), "");
  expect_error("wide.png", header_only(70000, 2), "");
  expect_error("many.png", header_only(60000, 60000), "beyond mvtm's limits");
}

// Fuzzing found an 877-byte file whose tEXt chunk claims 1.9 GB: libpng allocated (and touched)
// the claim before finding the file cut short. Metadata chunks are skipped unread; what they
// hold never changes the pixels, and a claim beyond the file costs no memory.
TEST_F(PngTest, MetadataChunksAreSkippedUnreadWhateverTheyClaim) {
  std::mt19937 rng(11);
  const std::string plain = MakePng({24, 16, 8, 2, 0, ""}, rng);
  const std::string head = plain.substr(0, 33);  // signature and IHDR
  const std::string rest = plain.substr(33);     // IDAT, IEND
  const std::vector<float> want = ReadImage(Write("plain.png", plain)).data;
  // Legitimate metadata (200 kB of text, a compressed text, an Exif block) before the pixels.
  const std::string meta =
      Chunk("tEXt", "Comment" + std::string(1, '\0') + std::string(200000, 'x')) +
      Chunk("zTXt", std::string("Title\0\0", 7) + "not deflate") +
      Chunk("eXIf", std::string("MM\0*garbage", 11));
  EXPECT_EQ(ReadImage(Write("meta.png", head + meta + rest)).data, want);
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  // A tEXt chunk claiming 1.9 GB, the file ending 700 bytes later.
  const std::string claim = Be32(1919247636) + "tEXt" + std::string(700, 'a');
  for (const std::string name : {"claim.png", "claim_spec.png"}) {
    const std::string path = Write(name, head + claim);
    try {
      if (name == "claim.png") {
        ReadImage(path);
      } else {
        ReadImageSpec(path);
      }
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(path + ": cannot read image"), std::string::npos)
          << e.what();
    }
  }
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024) << "kB of peak memory more";
}

}  // namespace
}  // namespace mvtm

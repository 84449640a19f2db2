#include "image/exr_io.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStdIO.h>
#include <ImfStringAttribute.h>
#include <ImfTileDescription.h>
#include <ImfTileDescriptionAttribute.h>
#include <ImfVersion.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "base/error.h"
#include "image/codec.h"

namespace mvtm {

namespace {

// The first 8 bytes: the magic number and the version field with its flags.
bool ReadMagic(const std::string& path, unsigned char head[8]) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  const bool ok = std::fread(head, 1, 8, f) == 8;
  std::fclose(f);
  return ok && Imf::isImfMagic(reinterpret_cast<const char*>(head));
}

// OpenEXR allocates what a header attribute claims before reading it (fuzzing found a 400-byte
// file claiming 430 MB), so the attribute sizes of every header are checked against the file
// first. Throws Error for a size beyond the end of the file.
void CheckAttributeSizes(const std::string& path, bool multipart) {
  std::ifstream in(path, std::ios::binary);
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (!in || ec) throw Error(path, 0, "cannot open");
  in.seekg(8);
  auto read_name = [&](std::string* out) {  // up to 255 characters and a NUL
    out->clear();
    for (char c; in.get(c);) {
      if (c == 0) return true;
      if (out->size() >= 255) return false;
      out->push_back(c);
    }
    return false;
  };
  const auto fail = [&](const std::string& what) {
    throw Error(path, 0, "cannot read image: corrupt or truncated file: " + what);
  };
  for (int header = 0;; ++header) {
    std::string name, type;
    int attributes = 0;
    for (;; ++attributes) {
      if (!read_name(&name)) fail("header cut short");
      if (name.empty()) break;
      unsigned char b[4];
      if (!read_name(&type) || !in.read(reinterpret_cast<char*>(b), 4)) fail("header cut short");
      const int64_t n = int32_t(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 |
                                uint32_t(b[3]) << 24);
      const uint64_t at = uint64_t(in.tellg());
      if (n < 0 || at + uint64_t(n) > size)
        fail("attribute '" + name + "' claims " + std::to_string(n) + " bytes at offset " +
             std::to_string(at) + " of a " + std::to_string(size) + "-byte file");
      in.seekg(std::streamoff(n), std::ios::cur);
    }
    if (!multipart || attributes == 0) return;  // a multi-part file ends with an empty header
  }
}

// The channel names in the order mvtm returns them, or empty when OpenImageIO should read it.
std::vector<std::string> ChannelOrder(const Imf::ChannelList& list, Imf::PixelType* type) {
  std::vector<std::string> names;
  bool first = true;
  for (auto it = list.begin(); it != list.end(); ++it) {
    const Imf::Channel& c = it.channel();
    if (c.xSampling != 1 || c.ySampling != 1 || (c.type != Imf::HALF && c.type != Imf::FLOAT))
      return {};
    if (!first && c.type != *type) return {};
    *type = c.type, first = false;
    names.push_back(it.name());
  }
  if (names.size() == 1) return names;
  // OpenImageIO orders R, G, B, A first; the sets mvtm writes are exactly these prefixes.
  static const std::vector<std::string> kRgba = {"R", "G", "B", "A"};
  if (names.size() < 2 || names.size() > 4) return {};
  std::vector<std::string> want(kRgba.begin(), kRgba.begin() + long(names.size()));
  std::vector<std::string> sorted = want;
  std::sort(sorted.begin(), sorted.end());
  return names == sorted ? want : std::vector<std::string>{};  // the file lists them sorted
}

// An in-memory output stream for Imf::OutputFile (it seeks back to write the offset table).
class MemoryStream : public Imf::OStream {
 public:
  explicit MemoryStream(std::vector<unsigned char>* out) : Imf::OStream("memory"), out_(out) {}
  void write(const char c[], int n) override {
    if (pos_ + size_t(n) > out_->size()) out_->resize(pos_ + size_t(n));
    std::memcpy(out_->data() + pos_, c, size_t(n));
    pos_ += size_t(n);
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = size_t(pos); }

 private:
  std::vector<unsigned char>* out_;
  size_t pos_ = 0;
};

}  // namespace

bool IsExrFile(const std::string& path) {
  unsigned char head[8];
  return ReadMagic(path, head);
}

bool ReadExr(const std::string& path, bool header_only, Image* img) {
  unsigned char head[8];
  if (!ReadMagic(path, head)) return false;
  const int version = head[4] | (head[5] << 8) | (head[6] << 16) | (head[7] << 24);
  CheckAttributeSizes(path, Imf::isMultiPart(version));
  // mvtm writes single-part scan-line or tiled images; OpenImageIO would read multi-part and
  // deep files without the checks below.
  if (Imf::isMultiPart(version) || Imf::isNonImage(version))
    throw Error(path, 0, "cannot read image: multi-part and deep OpenEXR files are not supported");
  static std::once_flag limits;
  std::call_once(limits, [] {  // sanityCheck() refuses larger windows and tiles
    Imf::Header::setMaxImageSize(kMaxReadImageSide, kMaxReadImageSide);
    Imf::Header::setMaxTileSize(kMaxReadImageSide, kMaxReadImageSide);
  });
  try {
    // The header alone first: sizes and channels are checked before OpenEXR sizes its buffers.
    Imf::Header h;
    {
      Imf::StdIFStream is(path.c_str());
      is.seekg(8);
      int v = version;
      h.readFrom(is, v);
      h.sanityCheck(Imf::isTiled(version));
    }
    const Imath::Box2i dw = h.dataWindow();
    const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, hgt = int64_t(dw.max.y) - dw.min.y + 1;
    int64_t listed = 0;
    for (auto it = h.channels().begin(); it != h.channels().end(); ++it) ++listed;
    CheckImageDims(path, w, hgt, listed);
    // Deflate expands at most 1032:1 and run-length coding before it at most 128:1 more; a
    // file smaller than that share of its pixels was cut short (or lies): refused before the
    // allocation.
    CheckHeaderFitsFile(path, w, hgt, double(w) * double(hgt) * double(listed) * 4, 4096.0,
                        1 << 20);
    // OpenEXR sizes its tile and line buffers from the tile size (up to 65536 a side), not the
    // image's: tiles larger than their image are refused like a header larger than its file
    // (a review: a 65536x1 image of 160x65535 tiles asks for 17 GB).
    if (Imf::isTiled(version) && h.hasTileDescription()) {
      const Imf::TileDescription& t = h.tileDescription();
      const double tile = double(std::max<int64_t>(w, t.xSize)) * double(t.ySize);
      if (tile > std::max(double(w) * double(hgt), double(1 << 20)))
        throw Error(path, 0,
                    "cannot read image: corrupt file: " + std::to_string(t.xSize) + "x" +
                        std::to_string(t.ySize) + " tiles in a " + std::to_string(w) + "x" +
                        std::to_string(hgt) + " image");
    }
    Imf::PixelType type = Imf::FLOAT;
    const std::vector<std::string> names = ChannelOrder(h.channels(), &type);
    if (names.empty()) return false;
    Image out;
    out.width = int(w), out.height = int(hgt), out.channels = int(names.size()), out.bits = 32;
    if (!header_only) {
      Imf::InputFile file(path.c_str());
      out.data.assign(out.pixels() * size_t(out.channels), 0.f);
      const size_t xs = sizeof(float) * size_t(out.channels), ys = xs * size_t(w);
      Imf::FrameBuffer fb;
      for (size_t c = 0; c < names.size(); ++c)
        fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, out.data.data() + c, dw, xs, ys));
      file.setFrameBuffer(fb);
      file.readPixels(dw.min.y, dw.max.y);
    }
    *img = std::move(out);
    return true;
  } catch (const Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw Error(path, 0, "cannot read image: out of memory");
  } catch (const std::exception& e) {
    throw Error(path, 0, "cannot read image: corrupt or truncated file: " + LibraryText(e.what()));
  }
}

std::vector<unsigned char> EncodeExr(const std::string& path, const Image& img) {
  if (img.bits != 32) throw Error(path, 0, "mvtm writes EXR as 32-bit float");
  static const char* kNames[4][4] = {{"Y"}, {"R", "G"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};
  if (img.channels < 1 || img.channels > 4)
    throw Error(path, 0,
                "mvtm writes EXR with 1 to 4 channels, not " + std::to_string(img.channels));
  std::vector<unsigned char> bytes;
  try {
    Imf::Header h(img.width, img.height);
    h.compression() = Imf::ZIP_COMPRESSION;
    h.insert("capDate", Imf::StringAttribute("1970:01:01 00:00:00"));
    for (int c = 0; c < img.channels; ++c)
      h.channels().insert(kNames[img.channels - 1][c], Imf::Channel(Imf::FLOAT));
    const size_t xs = sizeof(float) * size_t(img.channels), ys = xs * size_t(img.width);
    Imf::FrameBuffer fb;
    for (int c = 0; c < img.channels; ++c)
      fb.insert(kNames[img.channels - 1][c],
                Imf::Slice(Imf::FLOAT,
                           const_cast<char*>(reinterpret_cast<const char*>(img.data.data() + c)),
                           xs, ys));
    MemoryStream stream(&bytes);
    Imf::OutputFile out(stream, h);
    out.setFrameBuffer(fb);
    out.writePixels(img.height);
  } catch (const std::bad_alloc&) {
    throw Error(path, 0, "cannot encode image: out of memory");
  } catch (const std::exception& e) {
    throw Error(path, 0, "cannot encode image: " + LibraryText(e.what()));
  }
  return bytes;
}

}  // namespace mvtm

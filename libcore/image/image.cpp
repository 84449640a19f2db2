#include "image/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "base/atomic_file.h"
#include "base/error.h"
#include "image/png_io.h"

namespace mvtm {

namespace OIIO = OIIO_NAMESPACE;

namespace {
int BitsOf(const OIIO::TypeDesc& t) {
  if (t == OIIO::TypeDesc::UINT8 || t == OIIO::TypeDesc::INT8) return 8;
  if (t == OIIO::TypeDesc::UINT16 || t == OIIO::TypeDesc::INT16) return 16;
  return 32;
}

// OpenImageIO's messages can span lines ("PNG write error...\n..."); one line for the user.
std::string OneLine(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  // Library prefixes say nothing to a user ("OpenEXR exception: Cannot read image file ...").
  for (const char* prefix : {"OpenEXR exception: ", "Iex::BaseExc: "})
    if (s.rfind(prefix, 0) == 0) s = "corrupt or truncated file: " + s.substr(std::strlen(prefix));
  return s.empty() ? "unknown error" : s;
}
}  // namespace

// Refuses sizes no real image has before anything is allocated (a 58-byte PNG may claim
// 10^6 x 10^6 pixels).
void CheckImageSize(const std::string& path, const OIIO::ImageSpec& spec) {
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw Error(path, 0, "image has no pixels");
  const uint64_t pixels = uint64_t(spec.width) * uint64_t(spec.height);
  if (spec.width > kMaxReadImageSide || spec.height > kMaxReadImageSide || spec.nchannels > 16 ||
      pixels > kMaxImagePixels)
    throw Error(path, 0,
                "image claims " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                    "x" + std::to_string(spec.nchannels) +
                    ", beyond mvtm's limits (65536 pixels a side, 2^30 pixels, 16 channels)");
}

ImageSpecInfo ReadImageSpec(const std::string& path) {
  if (IsPngFile(path)) {
    Image h = ReadPng(path, true);
    return {h.width, h.height, h.channels, h.bits};
  }
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw Error(path, 0, "cannot read image: " + OneLine(OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  CheckImageSize(path, spec);
  return {spec.width, spec.height, spec.nchannels, BitsOf(spec.format)};
}

Image ReadImage(const std::string& path) {
  if (IsPngFile(path)) return ReadPng(path);
  // Keep colour values as stored: no premultiplication by alpha.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) throw Error(path, 0, "cannot read image: " + OneLine(OIIO::geterror()));
  const OIIO::ImageSpec& spec = in->spec();
  CheckImageSize(path, spec);
  Image img(spec.width, spec.height, spec.nchannels, BitsOf(spec.format));
  bool ok;
  if (img.bits == 32) {
    ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, img.data.data());
  } else if (img.bits == 16) {
    std::vector<uint16_t> buf(img.data.size());
    ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT16, buf.data());
    std::copy(buf.begin(), buf.end(), img.data.begin());
  } else {
    std::vector<uint8_t> buf(img.data.size());
    ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, buf.data());
    std::copy(buf.begin(), buf.end(), img.data.begin());
  }
  if (!ok) throw Error(path, 0, "cannot read image: " + OneLine(in->geterror()));
  return img;
}

Image ReadFloatMap(const std::string& path) {
  Image m = ReadImage(path);
  if (m.channels != 1 || m.bits != 32)
    throw Error(path, 0,
                "expected one 32-bit float channel (an EXR depth or confidence map), found " +
                    std::to_string(m.channels) + " channel(s) of " + std::to_string(m.bits) +
                    " bits");
  return m;
}

void RequireImageSize(const Image& img, const std::string& path, uint64_t w, uint64_t h) {
  if (uint64_t(img.width) != w || uint64_t(img.height) != h)
    throw Error(path, 0,
                "image is " + std::to_string(img.width) + "x" + std::to_string(img.height) +
                    " but its camera is " + std::to_string(w) + "x" + std::to_string(h));
}

namespace {
// Encodes `img` through `o` (already created for the path's format) into the file or proxy
// `target`. Returns false with o->geterror() set on failure.
bool Encode(OIIO::ImageOutput& o, const std::string& target, const Image& img) {
  OIIO::TypeDesc type = img.bits == 8    ? OIIO::TypeDesc::UINT8
                        : img.bits == 16 ? OIIO::TypeDesc::UINT16
                                         : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(img.width, img.height, img.channels, type);
  if (img.bits == 32) spec.attribute("compression", "zip");
  // OpenImageIO stamps the current time into EXR headers (capDate) unless DateTime is set; a
  // fixed value keeps outputs byte-identical across runs and shards.
  spec.attribute("DateTime", "1970:01:01 00:00:00");
  if (!o.open(target, spec)) return false;
  bool ok;
  if (img.bits == 32) {
    ok = o.write_image(OIIO::TypeDesc::FLOAT, img.data.data());
  } else {
    double maxv = img.MaxValue();
    if (img.bits == 16) {
      std::vector<uint16_t> buf(img.data.size());
      for (size_t i = 0; i < buf.size(); ++i)
        buf[i] = static_cast<uint16_t>(std::clamp(std::nearbyint(double(img.data[i])), 0.0, maxv));
      ok = o.write_image(OIIO::TypeDesc::UINT16, buf.data());
    } else {
      std::vector<uint8_t> buf(img.data.size());
      for (size_t i = 0; i < buf.size(); ++i)
        buf[i] = static_cast<uint8_t>(std::clamp(std::nearbyint(double(img.data[i])), 0.0, maxv));
      ok = o.write_image(OIIO::TypeDesc::UINT8, buf.data());
    }
  }
  return o.close() && ok;
}

}  // namespace

void WriteImage(const std::string& path, const Image& img) {
  if (img.empty()) throw Error(path, 0, "refusing to write an empty image");
  auto o = OIIO::ImageOutput::create(path);
  if (!o) throw Error(path, 0, "no image writer for this extension: " + OneLine(OIIO::geterror()));
  if (o->supports("ioproxy")) {
    // Encode in memory, then write the bytes with every write checked: OpenImageIO's file
    // writers do not report a full disk, which would leave a truncated file under its name.
    std::vector<unsigned char> bytes;
    OIIO::Filesystem::IOVecOutput proxy(bytes);
    if (!o->set_ioproxy(&proxy) || !Encode(*o, path, img))
      throw Error(path, 0, "cannot encode image: " + OneLine(o->geterror()));
    WriteBytesAtomic(path, bytes.data(), bytes.size());
    return;
  }
  // Other formats write their own file; read it back before it takes the final name.
  AtomicFile out(path);
  if (!Encode(*o, out.temp_path().string(), img))
    throw Error(path, 0, "cannot write image: " + OneLine(o->geterror()));
  try {
    ReadImage(out.temp_path().string());
  } catch (const Error&) {
    throw Error(path, 0, "write failed: the file does not read back (disk full?)");
  }
  out.Commit();
}

Image ToGrey(const Image& img) {
  if (img.channels == 1) return img;
  int colour = (img.channels == 2 || img.channels == 4) ? img.channels - 1 : img.channels;
  Image g(img.width, img.height, 1, img.bits);
  for (size_t p = 0; p < img.pixels(); ++p) {
    double s = 0;
    for (int c = 0; c < colour; ++c) s += img.data[p * img.channels + c];
    g.data[p] = static_cast<float>(s / colour);
  }
  return g;
}

}  // namespace mvtm

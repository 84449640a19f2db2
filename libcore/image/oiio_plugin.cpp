// libmvtm_oiio.so: reading and writing every other format through OpenImageIO (see
// oiio_plugin.h). Built as a module; only image.cpp's loader opens it.
#include "image/oiio_plugin.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <exception>

#include "base/error.h"
#include "image/codec.h"

namespace mvtm {
namespace {

namespace OIIO = OIIO_NAMESPACE;

int BitsOf(const OIIO::TypeDesc& t) {
  if (t == OIIO::TypeDesc::UINT8 || t == OIIO::TypeDesc::INT8) return 8;
  if (t == OIIO::TypeDesc::UINT16 || t == OIIO::TypeDesc::INT16) return 16;
  return 32;
}

// Runs `body`; an Error or any other exception becomes the returned message.
template <class F>
std::string Guard(F&& body) {
  try {
    return body();
  } catch (const Error& e) {  // the caller names the file itself
    std::string s = e.what();
    const std::string located = e.file() + ": ";
    return !e.file().empty() && s.rfind(located, 0) == 0 ? s.substr(located.size()) : s;
  } catch (const std::bad_alloc&) {
    return "out of memory";
  } catch (const std::exception& e) {
    return LibraryText(e.what());
  }
}

// A file is read by the reader its extension names, never by whichever of OpenImageIO's
// format plugins takes it: several allocate what their headers claim inside open(), before
// mvtm sees the spec (a review found PSD, SGI, FITS and GIF headers of a few bytes asking for
// gigabytes, each reachable from a .png or .jpg that the named reader declines).
void ReadByExtensionOnly() {
  static const bool once = OIIO::attribute("try_all_readers", 0);
  (void)once;
}

// Refuses what mvtm does not read (volumes, deep images) and tiles larger than their image
// (OpenImageIO sizes its tile buffers from the header), before read_image allocates.
void CheckLayout(const std::string& path, const OIIO::ImageSpec& spec) {
  if (spec.depth != 1 || spec.deep)
    throw Error(path, 0, "cannot read image: volume and deep images are not supported");
  if (spec.tile_width > 0) {
    const double tile = double(spec.tile_width) * std::max(spec.tile_height, 1) *
                        std::max(spec.tile_depth, 1) * spec.nchannels;
    const double image = double(spec.width) * spec.height * spec.nchannels;
    if (tile > std::max(image, double(1 << 20)))
      throw Error(path, 0,
                  "cannot read image: corrupt file: " + std::to_string(spec.tile_width) + "x" +
                      std::to_string(spec.tile_height) + " tiles in a " +
                      std::to_string(spec.width) + "x" + std::to_string(spec.height) + " image");
  }
}

std::string Read(const std::string& path, bool header_only, Image* img) {
  return Guard([&]() -> std::string {
    ReadByExtensionOnly();
    // Keep colour values as stored: no premultiplication by alpha.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) return "cannot read image: " + LibraryText(OIIO::geterror());
    const OIIO::ImageSpec& spec = in->spec();
    CheckImageDims(path, spec.width, spec.height, spec.nchannels);
    CheckLayout(path, spec);
    // No image format compresses real pictures beyond a few thousand to one; a header claiming
    // more than that share of the file was forged or cut short (fuzzing: a 30-byte file read as
    // a 7968x15485 WebP took 8 s and 3 GB).
    const double samples = double(spec.width) * spec.height * spec.nchannels;
    if (samples > double(1 << 24))
      CheckHeaderFitsFile(path, spec.width, spec.height, samples, 4096.0, 0);
    Image out;
    out.width = spec.width, out.height = spec.height, out.channels = spec.nchannels;
    out.bits = BitsOf(spec.format);
    if (header_only) {
      *img = std::move(out);
      return "";
    }
    out.data.resize(out.pixels() * size_t(out.channels));
    bool ok;
    if (out.bits == 32) {
      ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.data.data());
    } else if (out.bits == 16) {
      std::vector<uint16_t> buf(out.data.size());
      ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT16, buf.data());
      std::copy(buf.begin(), buf.end(), out.data.begin());
    } else {
      std::vector<uint8_t> buf(out.data.size());
      ok = in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, buf.data());
      std::copy(buf.begin(), buf.end(), out.data.begin());
    }
    if (!ok) return "cannot read image: " + LibraryText(in->geterror());
    *img = std::move(out);
    return "";
  });
}

// Encodes `img` through `o` (already created for the path's format) into `target`.
bool Encode(OIIO::ImageOutput& o, const std::string& target, const Image& img) {
  OIIO::TypeDesc type = img.bits == 8    ? OIIO::TypeDesc::UINT8
                        : img.bits == 16 ? OIIO::TypeDesc::UINT16
                                         : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(img.width, img.height, img.channels, type);
  if (img.bits == 32) spec.attribute("compression", "zip");
  // Colour is stored unassociated, as it was read.
  spec.attribute("oiio:UnassociatedAlpha", 1);
  // OpenImageIO stamps the current time into headers unless DateTime is set; a fixed value
  // keeps outputs byte-identical across runs and shards.
  spec.attribute("DateTime", "1970:01:01 00:00:00");
  if (!o.open(target, spec)) return false;
  bool ok;
  if (img.bits == 32) {
    ok = o.write_image(OIIO::TypeDesc::FLOAT, img.data.data());
  } else {
    const double maxv = img.MaxValue();
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

std::string Write(const std::string& path, const Image& img, const std::string& file_target,
                  std::vector<unsigned char>* bytes) {
  return Guard([&]() -> std::string {
    auto o = OIIO::ImageOutput::create(path);
    if (!o) return "no image writer for this extension: " + LibraryText(OIIO::geterror());
    if (o->supports("ioproxy")) {
      // Encoded in memory; the caller writes the bytes with every write checked (OpenImageIO's
      // file writers do not report a full disk).
      OIIO::Filesystem::IOVecOutput proxy(*bytes);
      if (!o->set_ioproxy(&proxy) || !Encode(*o, path, img))
        return "cannot encode image: " + LibraryText(o->geterror());
      return "";
    }
    bytes->clear();
    if (!Encode(*o, file_target, img)) return "cannot write image: " + LibraryText(o->geterror());
    return "";
  });
}

const OiioPlugin kPlugin{kOiioPluginAbi, Read, Write};

}  // namespace
}  // namespace mvtm

extern "C" __attribute__((visibility("default"))) const mvtm::OiioPlugin* mvtm_oiio_plugin() {
  return &mvtm::kPlugin;
}

#include "image/image.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>

#include "base/atomic_file.h"
#include "base/error.h"

namespace mvtm {

namespace OIIO = OIIO_NAMESPACE;

namespace {
int BitsOf(const OIIO::TypeDesc& t) {
  if (t == OIIO::TypeDesc::UINT8 || t == OIIO::TypeDesc::INT8) return 8;
  if (t == OIIO::TypeDesc::UINT16 || t == OIIO::TypeDesc::INT16) return 16;
  return 32;
}
}  // namespace

ImageSpecInfo ReadImageSpec(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw Error(path, 0, "cannot read image: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  return {spec.width, spec.height, spec.nchannels, BitsOf(spec.format)};
}

Image ReadImage(const std::string& path) {
  // Keep colour values as stored: no premultiplication by alpha.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) throw Error(path, 0, "cannot read image: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw Error(path, 0, "image has no pixels");
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
  if (!ok) throw Error(path, 0, "cannot read image: " + in->geterror());
  return img;
}

void WriteImage(const std::string& path, const Image& img) {
  if (img.empty()) throw Error(path, 0, "refusing to write an empty image");
  AtomicFile out(path);
  auto o = OIIO::ImageOutput::create(path);
  if (!o) throw Error(path, 0, "no image writer for this extension: " + OIIO::geterror());
  OIIO::TypeDesc type = img.bits == 8    ? OIIO::TypeDesc::UINT8
                        : img.bits == 16 ? OIIO::TypeDesc::UINT16
                                         : OIIO::TypeDesc::FLOAT;
  OIIO::ImageSpec spec(img.width, img.height, img.channels, type);
  if (img.bits == 32) spec.attribute("compression", "zip");
  // OpenImageIO stamps the current time into EXR headers (capDate) unless DateTime is set; a
  // fixed value keeps outputs byte-identical across runs and shards.
  spec.attribute("DateTime", "1970:01:01 00:00:00");
  if (!o->open(out.temp_path().string(), spec))
    throw Error(path, 0, "cannot write image: " + o->geterror());
  bool ok;
  if (img.bits == 32) {
    ok = o->write_image(OIIO::TypeDesc::FLOAT, img.data.data());
  } else {
    double maxv = img.MaxValue();
    if (img.bits == 16) {
      std::vector<uint16_t> buf(img.data.size());
      for (size_t i = 0; i < buf.size(); ++i)
        buf[i] = static_cast<uint16_t>(std::clamp(std::nearbyint(double(img.data[i])), 0.0, maxv));
      ok = o->write_image(OIIO::TypeDesc::UINT16, buf.data());
    } else {
      std::vector<uint8_t> buf(img.data.size());
      for (size_t i = 0; i < buf.size(); ++i)
        buf[i] = static_cast<uint8_t>(std::clamp(std::nearbyint(double(img.data[i])), 0.0, maxv));
      ok = o->write_image(OIIO::TypeDesc::UINT8, buf.data());
    }
  }
  if (!ok || !o->close()) throw Error(path, 0, "cannot write image: " + o->geterror());
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

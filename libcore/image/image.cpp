#include "image/image.h"

#include <algorithm>
#include <filesystem>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/plugin.h"
#include "image/codec.h"
#include "image/exr_io.h"
#include "image/jpeg_io.h"
#include "image/oiio_plugin.h"
#include "image/png_io.h"

namespace mvtm {

namespace {

// The OpenImageIO plugin, opened once per process. Throws Error(path, 0, ...) naming the file
// that needed it.
const OiioPlugin& Plugin(const std::string& path) {
  static std::string failure;
  static const OiioPlugin* plugin =
      PluginTable<OiioPlugin>("libmvtm_oiio.so", "mvtm_oiio_plugin", kOiioPluginAbi, &failure);
  if (!plugin)
    throw Error(path, 0,
                "this image format needs OpenImageIO, which could not be loaded: " + failure);
  return *plugin;
}

// Reads through the format's own library when it takes the file, else through OpenImageIO.
Image Read(const std::string& path, bool header_only) {
  Image img;
  if (IsPngFile(path)) return ReadPng(path, header_only);
  if (IsExrFile(path) && ReadExr(path, header_only, &img)) return img;
  if (IsJpegFile(path) && ReadJpeg(path, header_only, &img)) return img;
  if (!std::filesystem::exists(path)) throw Error(path, 0, "cannot read image: no such file");
  const std::string err = Plugin(path).read(path, header_only, &img);
  if (!err.empty()) throw Error(path, 0, err);
  return img;
}

std::string Extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace

ImageSpecInfo ReadImageSpec(const std::string& path) {
  Image h = Read(path, true);
  return {h.width, h.height, h.channels, h.bits};
}

Image ReadImage(const std::string& path) { return Read(path, false); }

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

// The pipeline's formats (8/16-bit PNG, float EXR, at most 4 channels) encoded in memory by their
// own library; false for anything else.
bool EncodeOwnFormat(const std::string& path, const Image& img, PngCompression png,
                     std::vector<unsigned char>* bytes) {
  const std::string ext = Extension(path);
  if (ext == ".png" && (img.bits == 8 || img.bits == 16) && img.channels <= 4) {
    *bytes = EncodePng(path, img, png);
    return true;
  }
  if (ext == ".exr" && img.bits == 32 && img.channels <= 4) {
    *bytes = EncodeExr(path, img);
    return true;
  }
  return false;
}

}  // namespace

void WriteImage(const std::string& path, const Image& img, PngCompression png) {
  if (img.empty()) throw Error(path, 0, "refusing to write an empty image");
  // The pipeline's formats: encoded in memory, then written with every write() and the close()
  // checked, so a full disk never leaves a truncated file in place.
  std::vector<unsigned char> own;
  if (EncodeOwnFormat(path, img, png, &own)) {
    WriteBytesAtomic(path, own.data(), own.size());
    return;
  }
  // Everything else through OpenImageIO: in memory when its writer can, else into a temporary
  // file that must read back before it takes the final name.
  AtomicFile out(path);
  std::vector<unsigned char> bytes;
  const std::string err = Plugin(path).write(path, img, out.temp_path().string(), &bytes);
  if (!err.empty()) throw Error(path, 0, err);
  if (!bytes.empty()) {
    WriteBytesAtomic(path, bytes.data(), bytes.size());
    return;
  }
  try {
    ReadImage(out.temp_path().string());
  } catch (const Error&) {
    throw Error(path, 0, "write failed: the file does not read back (disk full?)");
  }
  out.Commit();
}

void WriteImagesTogether(const std::vector<ImageToWrite>& images) {
  std::vector<std::vector<unsigned char>> bytes(images.size());
  std::vector<FileWriter> files;
  for (size_t i = 0; i < images.size(); ++i) {
    const ImageToWrite& w = images[i];
    if (w.image->empty()) throw Error(w.path, 0, "refusing to write an empty image");
    if (!EncodeOwnFormat(w.path, *w.image, PngCompression::kDefault, &bytes[i]))
      throw Error(w.path, 0,
                  "only 8/16-bit PNG and float EXR images are written together (program error)");
    const std::vector<unsigned char>& b = bytes[i];
    files.push_back({w.path, [&b](std::ostream& os) {
                       os.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
                     }});
  }
  WriteTogetherAtomic(files, true);
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

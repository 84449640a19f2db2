#include "image/jpeg_io.h"

// jpeglib.h needs size_t and FILE declared first.
#include <cstddef>
#include <cstdio>
// clang-format off
#include <jpeglib.h>
#include <jerror.h>
// clang-format on

#include <csetjmp>

#include "base/error.h"
#include "image/codec.h"

namespace mvtm {

namespace {

// libjpeg reports through this manager; errors longjmp back, nothing is printed.
struct ErrorManager {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = "";
  bool truncated = false;
};

void OnError(j_common_ptr cinfo) {
  auto* e = reinterpret_cast<ErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, e->message);
  std::longjmp(e->jump, 1);
}

// Warnings: a premature end of data is kept (the file was cut short), the rest is ignored.
void OnMessage(j_common_ptr cinfo, int level) {
  auto* e = reinterpret_cast<ErrorManager*>(cinfo->err);
  if (level < 0 && cinfo->err->msg_code == JWRN_JPEG_EOF) e->truncated = true;
}

// Real progressive files have about ten scans; libjpeg sets no limit, and each scan walks every
// block of the image (a review: a 4 kB file of 400 scans over 42 million pixels decodes for
// seconds). More than this many scans is refused, as djpeg -maxscans does.
constexpr int kMaxScans = 100;

void CountScans(j_common_ptr cinfo) {
  if (!cinfo->is_decompressor) return;
  const int scan = reinterpret_cast<j_decompress_ptr>(cinfo)->input_scan_number;
  if (scan <= kMaxScans) return;
  auto* e = reinterpret_cast<ErrorManager*>(cinfo->err);
  std::snprintf(e->message, sizeof e->message, "corrupt file: more than %d scans", kMaxScans);
  std::longjmp(e->jump, 1);
}

struct Decompress {
  jpeg_decompress_struct cinfo{};
  bool created = false;
  ~Decompress() {
    if (created) jpeg_destroy_decompress(&cinfo);
  }
};

struct File {
  std::FILE* f = nullptr;
  ~File() {
    if (f) std::fclose(f);
  }
};

}  // namespace

bool IsJpegFile(const std::string& path) {
  File f;
  f.f = std::fopen(path.c_str(), "rb");
  unsigned char head[3];
  return f.f && std::fread(head, 1, 3, f.f) == 3 && head[0] == 0xFF && head[1] == 0xD8 &&
         head[2] == 0xFF;
}

namespace {
// The libjpeg calls, in frames that hold no C++ object (a longjmp skips destructors).
// Returns false when libjpeg reported an error (message in `e`).
bool ReadHeader(jpeg_decompress_struct* cinfo, ErrorManager* e, std::FILE* f, bool* created,
                bool* leave_to_oiio) {
  if (setjmp(e->jump) != 0) return false;
  jpeg_create_decompress(cinfo);
  *created = true;
  jpeg_stdio_src(cinfo, f);
  jpeg_read_header(cinfo, TRUE);
  const J_COLOR_SPACE cs = cinfo->jpeg_color_space;
  if (cs == JCS_CMYK || cs == JCS_YCCK || cinfo->num_components == 2 || cinfo->num_components > 4) {
    *leave_to_oiio = true;
    return true;
  }
  cinfo->out_color_space = cinfo->num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_calc_output_dimensions(cinfo);
  return true;
}

bool Decode(jpeg_decompress_struct* cinfo, ErrorManager* e, JSAMPROW* rows) {
  if (setjmp(e->jump) != 0) return false;
  jpeg_start_decompress(cinfo);
  while (cinfo->output_scanline < cinfo->output_height)
    jpeg_read_scanlines(cinfo, rows + cinfo->output_scanline,
                        cinfo->output_height - cinfo->output_scanline);
  jpeg_finish_decompress(cinfo);
  return true;
}

// The scans (SOS markers) of a JPEG file, counted by walking its marker segments (a segment's
// payload is skipped by its length; entropy-coded data ends at the first 0xFF not followed by 0
// or a restart marker). For the files OpenImageIO reads (CMYK, YCCK, unusual component counts):
// its reader takes in every scan inside open(), with no progress monitor to stop it.
int ScansInFile(std::FILE* f) {
  std::rewind(f);
  int scans = 0, c = 0;
  if (std::fgetc(f) != 0xFF || std::fgetc(f) != 0xD8) return 0;
  for (;;) {
    while ((c = std::fgetc(f)) != EOF && c != 0xFF) {
    }
    while (c == 0xFF) c = std::fgetc(f);  // fill bytes
    if (c == EOF || c == 0xD9) return scans;
    if (c == 0x00 || c == 0x01 || (c >= 0xD0 && c <= 0xD7)) continue;  // stuffed byte, RSTn
    const int hi = std::fgetc(f), lo = std::fgetc(f);
    if (hi == EOF || lo == EOF || ((hi << 8) | lo) < 2) return scans;  // cut short, corrupt
    if (c == 0xDA && ++scans > kMaxScans) return scans;
    if (std::fseek(f, long((hi << 8) | lo) - 2, SEEK_CUR) != 0) return scans;
  }
}

// A JPEG compresses at most about 1:5000 (an all-grey image); smaller than that share of its
// pixels, the file was cut short (or lies): refused before the decoder allocates.
void CheckFitsFile(const std::string& path, int64_t w, int64_t h, int channels) {
  CheckHeaderFitsFile(path, w, h, double(w) * double(h) * channels, 10000.0, 1 << 20);
}

[[noreturn]] void Fail(const std::string& path, const ErrorManager& e) {
  throw Error(path, 0, std::string("cannot read image: ") + (e.message[0] ? e.message : "?"));
}
}  // namespace

bool ReadJpeg(const std::string& path, bool header_only, Image* img) {
  File f;
  f.f = std::fopen(path.c_str(), "rb");
  if (!f.f) throw Error(path, 0, "cannot open");
  ErrorManager errors;
  jpeg_progress_mgr progress{};  // outlives d: d.cinfo points at it
  Decompress d;
  d.cinfo.err = jpeg_std_error(&errors.mgr);
  errors.mgr.error_exit = OnError;
  errors.mgr.emit_message = OnMessage;
  bool leave_to_oiio = false;
  if (!ReadHeader(&d.cinfo, &errors, f.f, &d.created, &leave_to_oiio)) Fail(path, errors);
  if (leave_to_oiio) {
    // OpenImageIO's reader decodes inside open(), before mvtm sees its spec: checked here.
    CheckImageDims(path, d.cinfo.image_width, d.cinfo.image_height, d.cinfo.num_components);
    CheckFitsFile(path, d.cinfo.image_width, d.cinfo.image_height, d.cinfo.num_components);
    if (d.cinfo.progressive_mode && ScansInFile(f.f) > kMaxScans)
      throw Error(
          path, 0,
          "cannot read image: corrupt file: more than " + std::to_string(kMaxScans) + " scans");
    return false;
  }
  CheckImageDims(path, d.cinfo.output_width, d.cinfo.output_height, d.cinfo.output_components);
  Image out;
  out.width = int(d.cinfo.output_width), out.height = int(d.cinfo.output_height);
  out.channels = d.cinfo.output_components, out.bits = 8;
  if (header_only) {
    *img = std::move(out);
    return true;
  }
  CheckFitsFile(path, out.width, out.height, out.channels);
  progress.progress_monitor = CountScans;
  d.cinfo.progress = &progress;
  const size_t rowbytes = size_t(out.width) * size_t(out.channels);
  std::vector<unsigned char> buf(rowbytes * size_t(out.height));
  std::vector<JSAMPROW> rows(size_t(out.height));
  for (int y = 0; y < out.height; ++y) rows[size_t(y)] = buf.data() + rowbytes * size_t(y);
  if (!Decode(&d.cinfo, &errors, rows.data())) Fail(path, errors);
  if (errors.truncated)
    throw Error(path, 0, "cannot read image: corrupt or truncated file: premature end of data");
  out.data.assign(buf.begin(), buf.end());
  *img = std::move(out);
  return true;
}

}  // namespace mvtm

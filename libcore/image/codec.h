// mvtm — what the image codecs (png_io, exr_io, jpeg_io, the OpenImageIO plugin) share.
#pragma once

#include <cstdint>
#include <string>

namespace mvtm {

// Refuses sizes no real image has before anything is allocated (a 58-byte PNG may claim
// 10^6 x 10^6 pixels): Error(path, 0, ...) unless 1..kMaxReadImageSide a side, at most
// kMaxImagePixels pixels and 1..16 channels.
void CheckImageDims(const std::string& path, int64_t width, int64_t height, int64_t channels);

// Refuses a header that claims more than its file can hold, before the allocation: throws
// Error(path, 0, "cannot read image: the file (N bytes) is too small for its WxH header
// (truncated?)") when `raw` (bytes or samples the header implies) exceeds
// max_per_byte * file size + slack. Each codec passes its format's largest compression ratio.
// A file whose size cannot be read passes.
void CheckHeaderFitsFile(const std::string& path, int64_t width, int64_t height, double raw,
                         double max_per_byte, double slack);

// A library's message as one line a user can read: newlines folded, trailing blanks dropped,
// library prefixes ("OpenEXR exception: ", "Iex::BaseExc: ") said in words a user knows
// ("corrupt or truncated file: ").
std::string LibraryText(std::string s);

}  // namespace mvtm

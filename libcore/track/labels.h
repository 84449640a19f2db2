// mvtm — semantic label images → vehicle masks.
//
// Three kinds of label image (segtrack(1), section "Label images"):
//  * class ids (default): one channel, each sample an integer class id (8- or 16-bit); a pixel
//    is a vehicle when its id is one of `classes` (default 8, CamVid's Car).
//  * palette colours: three or four channels (alpha ignored); a pixel is a vehicle when its RGB
//    equals the palette colour of one of `classes`. The palette is an image whose pixels, in
//    row-major order, are the colours of class 0, 1, 2, ... (like CamVid's camvid11.png).
//  * binary: any channel count; a pixel is a vehicle when its first channel is non-zero.
// The output mask holds 1 for vehicle pixels and 0 elsewhere.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "image/image.h"

namespace mvtm {

class LabelDecoder {
 public:
  enum class Kind { kClassIds, kPalette, kBinary };

  // Class-id labels with these vehicle classes (each 0..65535). Throws UsageError when empty.
  static LabelDecoder ClassIds(const std::vector<int>& classes);
  // Palette labels: `palette` gives the colour of each class (first three channels, 8-bit).
  // Throws Error (naming `palette_name`) when a vehicle class has no colour in it.
  static LabelDecoder Palette(const Image& palette, const std::string& palette_name,
                              const std::vector<int>& classes);
  static LabelDecoder Binary();

  Kind kind() const { return kind_; }

  // Writes label.width*label.height bytes into `out` (resized). Throws Error("NAME: ...") when
  // the image does not fit the kind (channel count, a class id that is not an integer).
  void Decode(const Image& label, const std::string& name, std::vector<uint8_t>& out) const;

  // Parses "8" or "8,10,11" (the --classes syntax). Throws UsageError naming the bad item.
  static std::vector<int> ParseClasses(const std::string& text);

 private:
  Kind kind_ = Kind::kClassIds;
  static constexpr size_t kCompareClasses = 3;  // up to this many: compare, else look up
  std::vector<uint8_t> lut_;                    // class ids: 65536 entries, 1 = vehicle class
  std::vector<float> ids_;                      // class ids: the vehicle classes, each once
  std::vector<std::array<uint8_t, 3>> rgb_;     // palette: the vehicle colours
};

}  // namespace mvtm

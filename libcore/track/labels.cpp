#include "track/labels.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "base/error.h"

namespace mvtm {

LabelDecoder LabelDecoder::ClassIds(const std::vector<int>& classes) {
  if (classes.empty()) throw FieldError("classes", "at least one vehicle class id is needed");
  LabelDecoder d;
  d.kind_ = Kind::kClassIds;
  d.lut_.assign(65536, 0);
  for (int c : classes) {
    if (c < 0 || c > 65535)
      throw FieldError("classes", "id " + std::to_string(c) + " is outside 0..65535");
    if (!d.lut_[static_cast<size_t>(c)]) d.ids_.push_back(static_cast<float>(c));
    d.lut_[static_cast<size_t>(c)] = 1;
  }
  return d;
}

LabelDecoder LabelDecoder::Palette(const Image& palette, const std::string& palette_name,
                                   const std::vector<int>& classes) {
  if (classes.empty()) throw FieldError("classes", "at least one vehicle class id is needed");
  if (palette.channels < 3)
    throw Error(palette_name + ": a palette needs 3 or 4 channels (RGB), it has " +
                std::to_string(palette.channels));
  if (palette.bits != 8) throw Error(palette_name + ": a palette must be 8-bit");
  LabelDecoder d;
  d.kind_ = Kind::kPalette;
  for (int c : classes) {
    if (c < 0 || static_cast<size_t>(c) >= palette.pixels())
      throw Error(palette_name + ": no colour for class " + std::to_string(c) +
                  " (the palette has " + std::to_string(palette.pixels()) + ")");
    const float* p = palette.data.data() + static_cast<size_t>(c) * palette.channels;
    d.rgb_.push_back(
        {static_cast<uint8_t>(p[0]), static_cast<uint8_t>(p[1]), static_cast<uint8_t>(p[2])});
  }
  return d;
}

LabelDecoder LabelDecoder::Binary() {
  LabelDecoder d;
  d.kind_ = Kind::kBinary;
  return d;
}

std::vector<int> LabelDecoder::ParseClasses(const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    long v = -1;
    try {
      v = std::stol(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (item.empty() || used != item.size() || v < 0 || v > 65535)
      throw FieldError("classes",
                       "'" + item + "' is not a class id 0..65535 (want e.g. 8 or 8,10)");
    out.push_back(static_cast<int>(v));
  }
  if (out.empty() || (!text.empty() && text.back() == ','))
    throw FieldError("classes", "'" + text + "' is not a list of class ids (want e.g. 8 or 8,10)");
  return out;
}

void LabelDecoder::Decode(const Image& label, const std::string& name,
                          std::vector<uint8_t>& out) const {
  const size_t n = label.pixels();
  out.resize(n);
  const float* in = label.data.data();
  const int ch = label.channels;
  switch (kind_) {
    case Kind::kClassIds: {
      if (ch != 1)
        throw Error(name + ": class-id labels need 1 channel, this image has " +
                    std::to_string(ch) + " (colour labels: use --palette; masks: --binary)");
      if (label.bits == 32)
        throw Error(name + ": class-id labels must be 8- or 16-bit integers, not float");
      // 8/16-bit samples read as exact integers 0..65535: an id compares equal to its class,
      // and the table lookup needs no range check. A few classes: one comparison per class and
      // sample, which the compiler vectorises, costs less than the table's scattered loads.
      uint8_t* o = out.data();
      if (ids_.size() <= kCompareClasses) {
        const float first = ids_[0];
        for (size_t i = 0; i < n; ++i) o[i] = static_cast<uint8_t>(in[i] == first);
        for (size_t k = 1; k < ids_.size(); ++k) {
          const float id = ids_[k];
          for (size_t i = 0; i < n; ++i) o[i] |= static_cast<uint8_t>(in[i] == id);
        }
      } else {
        const uint8_t* lut = lut_.data();
        for (size_t i = 0; i < n; ++i) o[i] = lut[static_cast<uint32_t>(in[i])];
      }
      break;
    }
    case Kind::kPalette: {
      if (ch < 3)
        throw Error(name + ": palette labels need 3 or 4 channels (RGB), this image has " +
                    std::to_string(ch));
      if (label.bits != 8) throw Error(name + ": palette labels must be 8-bit");
      for (size_t i = 0; i < n; ++i) {
        const float* p = in + i * ch;
        uint8_t v = 0;
        for (const auto& c : rgb_)
          v |= static_cast<uint8_t>(p[0] == c[0] && p[1] == c[1] && p[2] == c[2]);
        out[i] = v;
      }
      break;
    }
    case Kind::kBinary: {
      for (size_t i = 0; i < n; ++i) out[i] = static_cast<uint8_t>(in[i * ch] != 0.f);
      break;
    }
  }
}

}  // namespace mvtm

#include "track/labels.h"

#include <gtest/gtest.h>

#include "base/error.h"

using namespace mvtm;

TEST(LabelDecoder, ClassIds) {
  Image im(3, 1, 1);
  im.data = {8, 3, 10};
  std::vector<uint8_t> out;
  LabelDecoder::ClassIds({8, 10}).Decode(im, "a.png", out);
  EXPECT_EQ(out, (std::vector<uint8_t>{1, 0, 1}));
  Image rgb(2, 1, 3);
  EXPECT_THROW(LabelDecoder::ClassIds({8}).Decode(rgb, "b.png", out), Error);
}

TEST(LabelDecoder, Palette) {
  Image pal(3, 1, 3);
  pal.data = {0, 0, 0, 10, 20, 30, 64, 0, 128};
  Image im(2, 2, 3);
  im.data = {64, 0, 128, 10, 20, 30, 64, 0, 127, 64, 0, 128};
  std::vector<uint8_t> out;
  LabelDecoder::Palette(pal, "p.png", {2}).Decode(im, "a.png", out);
  EXPECT_EQ(out, (std::vector<uint8_t>{1, 0, 0, 1}));
  EXPECT_THROW(LabelDecoder::Palette(pal, "p.png", {3}), Error);
}

TEST(LabelDecoder, BinaryAndParse) {
  Image im(3, 1, 2);
  im.data = {0, 255, 255, 0, 1, 0};
  std::vector<uint8_t> out;
  LabelDecoder::Binary().Decode(im, "a.png", out);
  EXPECT_EQ(out, (std::vector<uint8_t>{0, 1, 1}));
  EXPECT_EQ(LabelDecoder::ParseClasses("8,10"), (std::vector<int>{8, 10}));
  EXPECT_THROW(LabelDecoder::ParseClasses("8,x"), UsageError);
  EXPECT_THROW(LabelDecoder::ParseClasses(""), UsageError);
  EXPECT_THROW(LabelDecoder::ParseClasses("8,"), UsageError);
}

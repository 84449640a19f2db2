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

// Up to three classes are compared, more are looked up in a table: both give the same masks.
TEST(LabelDecoder, ClassIdsFewAndMany) {
  Image im(8, 1, 1, 16);
  im.data = {0, 8, 9, 10, 65535, 300, 8, 2};
  std::vector<uint8_t> out;
  LabelDecoder::ClassIds({8, 8, 65535}).Decode(im, "a.png", out);
  EXPECT_EQ(out, (std::vector<uint8_t>{0, 1, 0, 0, 1, 0, 1, 0}));
  LabelDecoder::ClassIds({2, 8, 300, 65535, 4}).Decode(im, "a.png", out);
  EXPECT_EQ(out, (std::vector<uint8_t>{0, 1, 0, 0, 1, 1, 1, 1}));
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

// A GoogleTest fixture holding one headless GL context for a whole test suite (libcore/render
// needs a current context; creating one per test would cost seconds on llvmpipe).
#pragma once

#include <gtest/gtest.h>

#include "render/context.h"

namespace mvtm {

class GlSuite : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ctx_ = GlContext::Create().release(); }
  static void TearDownTestSuite() {
    delete ctx_;
    ctx_ = nullptr;
  }
  static inline GlContext* ctx_ = nullptr;
};

}  // namespace mvtm

// mvtm — libFuzzer harness: the option-value parsers of libcore/cli (work.h, selection.h),
// run/option_table.h's choices and base/text.h. Byte 0 picks the parser (value mod 8); the rest is
// the option value. Accepts only mvtm::Error; see fuzz_util.h.
#include <string>
#include <vector>

#include "base/error.h"
#include "base/text.h"
#include "cli/selection.h"
#include "cli/work.h"
#include "fuzz_util.h"
#include "run/option_table.h"

namespace {

// Applies a selection to lists of several lengths, checking the indices it returns.
void CheckApply(const mvtm::Selection& s) {
  for (size_t n : {size_t{0}, size_t{1}, size_t{7}, size_t{100}}) {
    const std::vector<size_t> idx = s.Apply(n);
    size_t prev = 0;
    for (size_t k = 0; k < idx.size(); ++k) {
      if (idx[k] >= n || (k > 0 && idx[k] <= prev)) __builtin_trap();
      prev = idx[k];
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const int which = data[0] % 8;
  const std::string value = mvtm::fuzz::AsString(data + 1, size - 1);
  try {
    switch (which) {
      case 0: {
        const mvtm::ImageSize s = mvtm::ParseImageSize(value);
        if (s.width < 1 || s.height < 1 || s.width > mvtm::kMaxImageSide ||
            s.height > mvtm::kMaxImageSide)
          __builtin_trap();
        break;
      }
      case 1:
        CheckApply(mvtm::Selection::Frames(value));
        break;
      case 2:
        CheckApply(mvtm::Selection::Shard(value));
        break;
      case 3: {
        mvtm::WorkOptions w;
        const size_t colon = value.find('\n');
        w.frames = value.substr(0, colon);
        if (colon != std::string::npos) w.shard = value.substr(colon + 1);
        w.CheckWork();
        CheckApply(w.Select());
        w.ProvenanceName("tool");
        break;
      }
      case 4: {  // a declared choice option (run/option_table.h), as a command line sets it
        enum class Method { kKdtree, kBrute, kFlann, kGrid9 };
        Method m = Method::kKdtree;
        mvtm::OptionTable t("fuzz");
        t.Choice("--method", &m,
                 {{Method::kKdtree, "kdtree"},
                  {Method::kBrute, "brute"},
                  {Method::kFlann, "flann"},
                  {Method::kGrid9, "grid9"}},
                 "Method");
        t.Find("--method")->set(value);
        if (t.Find("--method")->text() != value) __builtin_trap();  // stored what was given
        break;
      }
      case 5:
        mvtm::ParseDoubleArg(value, "--value");
        break;
      case 6:
        mvtm::ParseIntArg(value, "--value");
        break;
      default: {
        mvtm::WorkOptions w;
        w.shard = value;
        w.CheckWork();
        w.ProvenanceName("tool");
        break;
      }
    }
  } catch (const mvtm::Error&) {
  }
  return 0;
}

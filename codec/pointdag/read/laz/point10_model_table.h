// 256 byte-valued models selected by the previous value of a field (POINT10's return bits,
// classification, user data). As in LASzip, a model comes to life when first selected in a chunk:
// most files use a handful of the 256, so only those are allocated (once per decoder) and reset.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "pointdag/read/laz/arithmetic_decoder.h"

namespace pointdag::laz {

class Point10ModelTable {
 public:
  // A new chunk: every model starts over at its first use.
  void Reset() { ready_.fill(false); }

  ArithmeticModel& Get(uint8_t previous) {
    if (!ready_[previous]) {
      if (models_[previous] == nullptr) {
        models_[previous] = std::make_unique<ArithmeticModel>(256);
      } else {
        models_[previous]->Reset();
      }
      ready_[previous] = true;
    }
    return *models_[previous];
  }

 private:
  std::array<std::unique_ptr<ArithmeticModel>, 256> models_;
  std::array<bool, 256> ready_{};
};

}  // namespace pointdag::laz

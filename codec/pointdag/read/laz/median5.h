// LASzip's running median of the last five coordinate differences (StreamingMedian5): the POINT10
// and POINT14 coders predict each x and y difference by it. The insertion order decides ties exactly as in
// LASzip, so the predictions (and hence the decoded points) match bit for bit.
#pragma once

#include <cstdint>

namespace pointdag::laz {

class Median5 {
 public:
  void Reset() {
    for (int32_t& v : values_) v = 0;
    high_ = true;
  }
  int32_t Get() const { return values_[2]; }

  // Alternately drops the largest and the smallest of the five, then inserts v in order.
  void Add(int32_t v) {
    int32_t* s = values_;
    if (high_) {
      if (v < s[2]) {
        s[4] = s[3];
        s[3] = s[2];
        if (v < s[0]) {
          s[2] = s[1];
          s[1] = s[0];
          s[0] = v;
        } else if (v < s[1]) {
          s[2] = s[1];
          s[1] = v;
        } else {
          s[2] = v;
        }
      } else {
        if (v < s[3]) {
          s[4] = s[3];
          s[3] = v;
        } else {
          s[4] = v;
        }
        high_ = false;
      }
    } else {
      if (s[2] < v) {
        s[0] = s[1];
        s[1] = s[2];
        if (s[4] < v) {
          s[2] = s[3];
          s[3] = s[4];
          s[4] = v;
        } else if (s[3] < v) {
          s[2] = s[3];
          s[3] = v;
        } else {
          s[2] = v;
        }
      } else {
        if (s[1] < v) {
          s[0] = s[1];
          s[1] = v;
        } else {
          s[0] = v;
        }
        high_ = true;
      }
    }
  }

 private:
  int32_t values_[5] = {0, 0, 0, 0, 0};
  bool high_ = true;
};

}  // namespace pointdag::laz

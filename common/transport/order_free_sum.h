// A sum of floats whose result does not depend on the order of its terms:
// for the photon-map estimate, whose photons come out of a search in an
// order that depends on how the search went (a guessed radius, a heap), so
// that no sort is needed for the same bits every time.
//
// Each term becomes a 64-bit fixed-point integer on a scale set by the
// largest magnitude among them (truncated toward zero: a term under about
// 2^-(61 - log2 count) of the largest, 2^-54 for 64 terms, contributes
// nothing, where float addition keeps 2^-24), and integers add exactly, in
// any order. The total is rounded once to double and once to float.
#pragma once

#include <bit>
#include <cmath>
#include <cstdint>

#include "common/math.h"

namespace portico {

class OrderFreeSum {
 public:
  // At most `count` terms, none of magnitude above `largest`.
  OrderFreeSum(float largest, uint32_t count) {
    if (!std::isfinite(largest)) {
      // An infinite or NaN term makes the float sum infinite or NaN in any
      // order.
      inFloat_ = true;
      return;
    }
    if (!(largest > 0)) return;   // every term is 0
    int exponent = 0;
    std::frexp(largest, &exponent);   // largest < 2^exponent
    // Each term below 2^(62 - bits of count), so count of them stay below
    // 2^62.
    const int shift = 62 - static_cast<int>(std::bit_width(count)) - exponent;
    scale_ = std::ldexp(1.0, shift);
    unscale_ = std::ldexp(1.0, -shift);
  }

  void add(const Vec3& term) {
    if (inFloat_) {
      floatSum_ += term;
      return;
    }
    for (int c = 0; c < 3; ++c) sum_[c] += static_cast<int64_t>(static_cast<double>(term[c]) * scale_);
  }

  Vec3 total() const {
    if (inFloat_) return floatSum_;
    return Vec3(static_cast<float>(static_cast<double>(sum_[0]) * unscale_),
                static_cast<float>(static_cast<double>(sum_[1]) * unscale_),
                static_cast<float>(static_cast<double>(sum_[2]) * unscale_));
  }

 private:
  double scale_ = 0, unscale_ = 0;
  int64_t sum_[3] = {0, 0, 0};
  bool inFloat_ = false;
  Vec3 floatSum_;
};

}  // namespace portico

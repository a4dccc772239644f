// The block rule of portico's image-error measures: an image is judged by
// square blocks, and a block dimmer than a fraction of the image mean is
// left out (its relative error would say more about its darkness than about
// the image). compareImages (against a reference) and the render passes'
// error estimate (coordinator/pass_error.h, without one) use the same rule.
#pragma once

namespace portico {

constexpr int kErrorBlockSize = 16;                 // pixels on a block's side
constexpr double kDimBlockFractionOfMean = 0.05;   // blocks at or under this x the image mean are skipped

}  // namespace portico

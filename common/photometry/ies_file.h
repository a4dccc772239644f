// An IES LM-63 photometric file (ANSI/IES LM-63-1995, -2002, -2019, and the
// older header-less and IESNA91 files): the luminaire's candela distribution
// over a grid of vertical and horizontal angles. Only what a luminaire in
// portico needs is read: TILT=NONE, photometric type C.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "common/photometry/candela_grid.h"
#include "common/photometry/luminous_opening.h"

namespace portico {

struct IesPhotometry {
  std::string standard;          // "LM-63-2002", "LM-63-1995", "LM-63-1991", "LM-63-2019", "LM-63-1986"
  int lampCount = 1;
  double lumensPerLamp = -1;     // -1: absolute photometry (the candela values are the luminaire's own)
  double candelaMultiplier = 1;
  double ballastFactor = 1;
  double ballastLampFactor = 1;  // LM-63-1995 and older only; later files give 1 (or another field there)
  double width = 0, length = 0, height = 0;   // luminous opening, metres (LM-63 signs: negative is round)
  LuminousOpening opening;                    // the shape those give (luminous_opening.h)
  // Candela values as given times the multiplier, the ballast factor and
  // (files before LM-63-2002) the ballast-lamp factor: what the luminaire
  // emits.
  CandelaGrid grid;
  // The lamps' rated lumens (lampCount x lumensPerLamp); -1 with absolute photometry.
  double ratedLumens() const { return lumensPerLamp < 0 ? -1 : lampCount * lumensPerLamp; }
};

// Throws std::runtime_error "NAME: line N: problem" (one line) for a file
// that is malformed, truncated, has a negative candela value, a luminous
// opening of none of LM-63's shapes, or uses what is not read (TILT=INCLUDE or a tilt file, photometric types A and B).
IesPhotometry parseIes(std::string_view text, const std::string& name);
// The same for a file on disk ("PATH: cannot be read" when it cannot).
IesPhotometry readIesFile(const std::string& path);

}  // namespace portico

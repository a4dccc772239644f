// `portico scene export STORE -o FILE.rad [--sky ... --sun ...]`: the store
// as a Radiance scene, so that portico's numbers can be checked with
// Radiance (`oconv`, `rtrace -I`) and Radiance users can bring their sensor
// files. Coordinates stay portico's (metres, +Y up), so a .pts file means
// the same points to both.
//  * Materials: `plastic` for diffuse ones (albedo as reflectance,
//    specularity and roughness 0), `light` for lamps (portico's radiance,
//    W m^-2 sr^-1 per channel, is Radiance's unit), `glass` for thin glass
//    (transmissivity from portico's transmittance, radianceGlassTransmissivity).
//  * Geometry: one `polygon` per triangle; a lamp that is a parallelogram of
//    two triangles (export_groups.h) one 4-sided polygon, as Radiance samples
//    a source best.
//  * Daylight (FILE.sky.rad, written when --sky or --sun is given): the CIE
//    overcast sky as gensky's `-c` sky turned to +Y up, the uniform sky as a
//    `glow` over sky and ground, the sun as a `light` source 0.53 degrees
//    across. Preetham's sky has no Radiance counterpart and is refused.
#pragma once

#include <string>

#include "common/job/job_settings.h"
#include "coordinator/cli/scene_export.h"

namespace portico::cli {

bool isRadiancePath(const std::string& path);   // *.rad

// FILE.sky.rad beside FILE.rad.
std::string radianceSkyPath(const std::string& radPath);

// Radiance's glass takes the transmissivity tn of the pane's material, and
// sums the reflections between its faces itself: at normal incidence it
// passes T = tn (1 - R)^2 / (1 - R^2 tn^2), R = ((n - 1) / (n + 1))^2.
// This is tn for which that T equals what a portico pane of this tint passes
// at normal incidence, tint x (1 - R') = tint (1 - R) / (1 + R)
// (thin_glass.h): tn = 1 for tint 1. For n = 1.52 it is Radiance's own
// formula, (sqrt(.8402528435 + .0072522239 T^2) - .9166530661) / .0036261119 / T.
double radianceGlassTransmissivity(double tint, double ior);

// Throws std::runtime_error naming the file or the option when the file
// cannot be written, the extension is not .rad or the sky has no Radiance
// counterpart (--sky preetham, or --sun without --sky).
ExportSummary exportStoreRadiance(const std::string& store, const std::string& radPath,
                                  const DaylightSettings& daylight);

}  // namespace portico::cli

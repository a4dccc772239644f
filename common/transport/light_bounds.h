// What a light tree knows of a group of lights (Conty Estevez & Kulla 2018,
// "Importance sampling of many lights with adaptive tree splitting"): the
// box around them, their luminous power, and the cone of directions they
// emit into (an axis, the spread of the lights' normals around it, and how
// far past their normals each emits: 90 degrees for a one-sided area
// light). From these, an importance at a shading point that is ZERO only
// when no light of the group can reach the point's upper side: the tree
// descends by importance, and a light it can never reach must truly be dark
// there, or the estimate is biased.
#pragma once

#include "common/math.h"

namespace portico {

struct LightBounds {
  Bounds3 box;
  float power = 0;            // luminous power (luminance of the RGB power); 0: empty
  Vec3 axis{0, 0, 1};         // unit
  float cosSpread = 1;        // cos theta_o: the normals lie within theta_o of the axis
  float cosEmission = 0;      // cos theta_e: each emits up to theta_e past its normal
};

// The bounds of both groups together (the cone around both cones).
LightBounds unite(const LightBounds& a, const LightBounds& b);

// What importance() reads of a LightBounds, computed once per node.
struct PreparedLightBounds {
  Vec3 center, half;          // the box's centre and half diagonal
  float radius = 0;           // of a sphere around the box
  float power = 0;
  Vec3 axis;
  float cosSpread = 1, sinSpread = 0, cosEmission = 0;
  float tilt = -1;            // 2 sin(theta_o / 2) where the half-space test applies, else < 0
};
PreparedLightBounds prepare(const LightBounds& bounds);

// How much light the group may send to `point` on a surface facing `normal`
// (unit), up to a constant: power x the largest emission cosine over the box
// x the largest receiving cosine / squared distance to the box's centre
// (at least its half diagonal squared). 0 when every direction from the box
// to the point is outside the emission cone or below the point's tangent
// plane.
float importance(const PreparedLightBounds& bounds, const Vec3& point, const Vec3& normal);

// The build's cost of a group (Conty Estevez & Kulla, eq. 3): power x the
// solid angle measure of its cone x the box's surface area, with pbrt-v4's
// regularisation against long thin boxes along `axis` (0-2).
double groupCost(const LightBounds& bounds, const Bounds3& parentBox, int axis);

}  // namespace portico

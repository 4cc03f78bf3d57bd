#pragma once
// atan2 for non-negative y with Cephes' rational approximation, for one double or two lanes: the
// angle off the axis of kb4 projections in the backend.

#include <cmath>
#include <numbers>

#include "voca/camera/double2.h"

namespace voca {

namespace camera_detail {

inline constexpr double kTan3Pi8 = 2.41421356237309504880;            // tan(3 pi / 8)
inline constexpr double kAtanMoreBits = 6.123233995736765886130e-17;  // pi/2 - double(pi/2)

// atan(t) for |t| <= tan(pi/8) plus base + extra: Cephes' rational approximation (S. L. Moshier),
// for double or Double2 alike.
template <typename T>
inline T atanReduced(T t, T base, T extra) {
  const T z = t * t;
  const T p = (((-8.750608600031904122785e-1 * z - 1.615753718733365076637e1) * z - 7.500855792314704667340e1) * z -
               1.228866684490136173410e2) *
                  z -
              6.485021904942025371773e1;
  const T q = ((((z + 2.485846490142306297962e1) * z + 1.650270098316988542046e2) * z + 4.328810604912902668951e2) * z +
               4.853903996359136964868e2) *
                  z +
              1.945506571482613964425e2;
  return base + ((t * (z * p / q) + t) + extra);
}

// atan2(y, x) for y >= 0 (an angle in [0, pi]) with Cephes' rational approximation of atan
// (the arguments reduced to |t| <= tan(pi/8) through pi/4 and pi/2), about three times as fast as
// the C library's correctly rounded one and within a few units in the last place of it
// (tests/test_camera.cpp). Only one division beyond the rational: x/y ratios are formed directly.
inline double atan2NonNegative(double y, double x) {
  const double ax = std::abs(x);
  // x = y = 0 gives 0 or pi, as std::atan2(+0, +-0).
  if (!(ax > 0.0) && !(y > 0.0)) return std::signbit(x) ? std::numbers::pi : 0.0;
  double angle;
  if (y > kTan3Pi8 * ax) {  // beyond 3 pi / 8: pi/2 - atan(|x| / y)
    angle = atanReduced(-ax / y, std::numbers::pi / 2, kAtanMoreBits);
  } else if (y <= 0.66 * ax) {
    angle = atanReduced(y / ax, 0.0, 0.0);
  } else {  // pi/4 + atan((y - |x|) / (y + |x|))
    angle = atanReduced((y - ax) / (y + ax), std::numbers::pi / 4, 0.5 * kAtanMoreBits);
  }
  // x < 0: the mirror image, pi - atan2(y, |x|).
  return x < 0.0 ? std::numbers::pi - angle : angle;
}

// The same in both lanes of a Double2 with y > 0 (the caller handles y = 0): every lane takes the
// operations of its own branch above (one division of the chosen numerator and denominator).
inline Double2 atan2NonNegative(Double2 y, Double2 x) {
  const Double2 ax = abs(x);
  const Mask2 steep = y > kTan3Pi8 * ax;
  const Mask2 flat = ~steep & (y <= 0.66 * ax);
  const Mask2 middle = ~steep & ~flat;
  const Double2 numerator = select(steep, -ax, select(flat, y, y - ax));
  const Double2 denominator = select(steep, y, select(flat, ax, y + ax));
  const Double2 zero{0.0, 0.0};
  const Double2 base = select(steep, zero + std::numbers::pi / 2, select(middle, zero + std::numbers::pi / 4, zero));
  const Double2 extra = select(steep, zero + kAtanMoreBits, select(middle, zero + 0.5 * kAtanMoreBits, zero));
  const Double2 angle = atanReduced(numerator / denominator, base, extra);
  return select(x < zero, std::numbers::pi - angle, angle);
}

}  // namespace camera_detail

}  // namespace voca

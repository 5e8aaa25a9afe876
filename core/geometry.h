// Segment-segment closest points (Eq 5-8), clamped to the segments and safe for
// parallel segments (Ericson, Real-Time Collision Detection, 5.1.9).
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace ravel {

// Closest points pa = p0 + s (p1 - p0) and pb = q0 + t (q1 - q0), s, t in [0, 1].
template <class V>
void closest_points_segments(const V& p0, const V& p1, const V& q0, const V& q1, typename V::Scalar& s,
                             typename V::Scalar& t, V& pa, V& pb) {
  using R = typename V::Scalar;
  const V d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const R a = d1.dot(d1), e = d2.dot(d2), f = d2.dot(r);
  const R eps = R(1e-30);
  if (a <= eps && e <= eps) {
    s = t = 0;
  } else if (a <= eps) {
    s = 0;
    t = std::clamp(f / e, R(0), R(1));
  } else {
    const R c = d1.dot(r);
    if (e <= eps) {
      t = 0;
      s = std::clamp(-c / a, R(0), R(1));
    } else {
      const R b = d1.dot(d2);
      const R denom = a * e - b * b;  // >= 0; ~0 when parallel
      s = denom > R(1e-12) * a * e ? std::clamp((b * f - c * e) / denom, R(0), R(1)) : R(0);
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, R(0), R(1));
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, R(0), R(1));
      }
    }
  }
  pa = p0 + s * d1;
  pb = q0 + t * d2;
}

}  // namespace ravel

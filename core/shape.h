// Projectile shapes as signed-distance functions (negative inside), so that contact
// (Eq 18-22) treats every shape alike: penetration = -sdf, normal = gradient of sdf.
// The sphere's sdf gives exactly the paper's test |x_node - x_proj| <= R (Eq 18).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "scene.h"

namespace ravel {

struct Shape {
  ShapeKind kind = ShapeKind::sphere;
  double radius = 6e-3;            // sphere / cylinder / cone base radius
  double length = 12e-3;           // cylinder length / cone height
  Eigen::Vector3d axis{0, 0, -1};  // unit, pointing forward (direction of flight)

  // Bounding radius about the centre, for cheap rejection.
  double bounding_radius() const {
    if (kind == ShapeKind::sphere) return radius;
    return std::sqrt(radius * radius + 0.25 * length * length);
  }

  // Signed distance of point p (relative to the shape's centre) and outward unit normal.
  template <class V>
  double sdf(const V& p_in, V& normal) const {
    using R = typename V::Scalar;
    if (kind == ShapeKind::sphere) {
      R r = p_in.norm();
      if (r > R(0))
        normal = p_in / r;
      else
        normal = -axis.cast<R>();
      return double(r) - radius;
    }
    // Local frame: h along the axis (forward positive), q radial distance.
    const V a = axis.cast<R>();
    const double h = double(p_in.dot(a));
    V radial = p_in - R(h) * a;
    const double q = double(radial.norm());
    V er = q > 1e-15 ? V(radial / R(q)) : V(orthogonal(a));
    if (kind == ShapeKind::cylinder) {
      // Capped cylinder centred on the centre, faces at h = +-length/2.
      const double dq = q - radius, dh = std::abs(h) - 0.5 * length;
      const V eh = h >= 0 ? a : V(-a);
      if (dq > 0 && dh > 0) {
        const double d = std::sqrt(dq * dq + dh * dh);
        normal = (R(dq) * er + R(dh) * eh) / R(d);
        return d;
      }
      if (dq > dh) {
        normal = er;
        return dq;
      }
      normal = eh;
      return dh;
    }
    // Cone: tip forward at h = +length/2, base disc at h = -length/2.
    const double half_h = 0.5 * length;
    const double slant = std::sqrt(radius * radius + length * length);
    const double cs = length / slant, sn = radius / slant;  // cos/sin of half angle
    // Distance to the lateral surface line in the (q, h) half-plane.
    const double tip_h = half_h;
    const double u = (tip_h - h);  // along the axis back from the tip
    // Signed distance to the infinite cone surface: positive outside.
    double d_side = q * cs - u * sn;
    double d_base = -half_h - h;  // positive behind the base
    // Beyond the tip or the base rim use point distances.
    const double along = q * sn + u * cs;  // projection on the slant line from the tip
    if (along < 0) {
      V rel = p_in - R(tip_h) * a;
      double d = double(rel.norm());
      normal = d > 0 ? V(rel / R(d)) : a;
      return d;
    }
    if (along > slant && d_base > -1e300) {
      // Past the rim: distance to the rim circle.
      V rim = R(-half_h) * a + R(radius) * er;
      V rel = p_in - rim;
      double d = double(rel.norm());
      if (d_side > 0 || d_base > 0) {
        normal = d > 0 ? V(rel / R(d)) : V(-a);
        return d;
      }
    }
    if (d_side > d_base) {
      normal = R(cs) * er + R(sn) * a;
      return d_side;
    }
    normal = -a;
    return d_base;
  }

 private:
  template <class V>
  static V orthogonal(const V& a) {
    V t = std::abs(a.x()) < 0.9 ? V(1, 0, 0) : V(0, 1, 0);
    V o = t - t.dot(a) * a;
    return o / o.norm();
  }
};

}  // namespace ravel

// Internal: the few vector / matrix helpers the renderer needs (column-major 4x4).
#pragma once

#include <array>
#include <cmath>

#include "render/renderer.h"

namespace ravel::render {

using Mat4 = std::array<float, 16>;

inline Vec3 operator+(const Vec3& a, const Vec3& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline Vec3 operator-(const Vec3& a, const Vec3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline Vec3 operator*(const Vec3& a, float s) {
  return {a[0] * s, a[1] * s, a[2] * s};
}
inline float dot(const Vec3& a, const Vec3& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline float length(const Vec3& a) {
  return std::sqrt(dot(a, a));
}
inline Vec3 normalize(const Vec3& a) {
  const float l = length(a);
  return l > 0 ? a * (1.0f / l) : Vec3{0, 0, 0};
}

inline Mat4 mul(const Mat4& a, const Mat4& b) {
  Mat4 r{};
  for (int c = 0; c < 4; ++c)
    for (int rr = 0; rr < 4; ++rr) {
      float s = 0;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + rr] * b[c * 4 + k];
      r[c * 4 + rr] = s;
    }
  return r;
}

inline std::array<float, 4> mul(const Mat4& m, const std::array<float, 4>& v) {
  std::array<float, 4> r{};
  for (int rr = 0; rr < 4; ++rr) r[rr] = m[rr] * v[0] + m[4 + rr] * v[1] + m[8 + rr] * v[2] + m[12 + rr] * v[3];
  return r;
}

constexpr float kDegToRad = 3.14159265358979f / 180.0f;

}  // namespace ravel::render

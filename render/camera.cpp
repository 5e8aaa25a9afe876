// Orbit camera, presets and fit-to-fabric.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include "render/math.h"
#include "render/renderer.h"

namespace ravel::render {

const char* to_string(ViewPreset v) {
  switch (v) {
    case ViewPreset::oblique:
      return "oblique";
    case ViewPreset::top:
      return "top";
    case ViewPreset::back:
      return "back";
    case ViewPreset::section:
      return "section";
  }
  return "?";
}

namespace {
constexpr ViewPreset kViewPresets[] = {ViewPreset::oblique, ViewPreset::top, ViewPreset::back, ViewPreset::section};
}  // namespace

bool parse_view_preset(const std::string& name, ViewPreset* out) {
  for (ViewPreset v : kViewPresets)
    if (name == to_string(v)) {
      *out = v;
      return true;
    }
  return false;
}

std::string view_preset_names() {
  std::string s;
  const std::size_t n = std::size(kViewPresets);
  for (std::size_t i = 0; i < n; ++i)
    s += (i == 0 ? "" : i + 1 == n ? " or " : ", ") + std::string(to_string(kViewPresets[i]));
  return s;
}

Camera Camera::preset(ViewPreset v) {
  Camera c;
  switch (v) {
    case ViewPreset::oblique:  // from above the impact face, front right
      c.yaw_deg = -62.0f;
      c.pitch_deg = 38.0f;
      break;
    case ViewPreset::top:  // straight down on the impact face, +y up on screen, +x right
      c.yaw_deg = -90.0f;
      c.pitch_deg = 90.0f;
      break;
    case ViewPreset::back:  // straight up at the back face, +y up on screen
      c.yaw_deg = 90.0f;
      c.pitch_deg = -90.0f;
      break;
    case ViewPreset::section:  // from -y at the cut plane y = impact point, slightly above
      c.yaw_deg = -90.0f;
      c.pitch_deg = 6.0f;
      break;
  }
  return c;
}

// Direction from the target to the eye.
static Vec3 eye_direction(float yaw_deg, float pitch_deg) {
  const float y = yaw_deg * kDegToRad, p = pitch_deg * kDegToRad;
  return {std::cos(p) * std::cos(y), std::cos(p) * std::sin(y), std::sin(p)};
}

Vec3 Camera::eye() const {
  return target + eye_direction(yaw_deg, pitch_deg) * distance_m;
}
Vec3 Camera::forward() const {
  return eye_direction(yaw_deg, pitch_deg) * -1.0f;
}
// Screen up is the derivative of the eye direction along pitch: defined even when
// looking straight down (pitch = +-90), where a fixed world-up vector would not be.
Vec3 Camera::up() const {
  const float y = yaw_deg * kDegToRad, p = pitch_deg * kDegToRad;
  return {-std::sin(p) * std::cos(y), -std::sin(p) * std::sin(y), std::cos(p)};
}
Vec3 Camera::right() const {
  return normalize(cross(forward(), up()));
}

void Camera::orbit(float d_yaw_deg, float d_pitch_deg) {
  yaw_deg = std::fmod(yaw_deg + d_yaw_deg, 360.0f);
  pitch_deg = std::clamp(pitch_deg + d_pitch_deg, -90.0f, 90.0f);
}

void Camera::zoom(float factor) {
  if (factor > 0) distance_m = std::clamp(distance_m * factor, 1e-4f, 1e3f);
}

void Camera::pan(float dx, float dy) {
  const float view_height = 2.0f * distance_m * std::tan(0.5f * fov_y_deg * kDegToRad);
  target = target + right() * (dx * view_height) + up() * (dy * view_height);
}

std::array<float, 16> Camera::view_matrix() const {
  const Vec3 f = forward(), r = right(), u = cross(r, f), e = eye();
  return {r[0], u[0], -f[0], 0, r[1], u[1], -f[1], 0, r[2], u[2], -f[2], 0, -dot(r, e), -dot(u, e), dot(f, e), 1};
}

std::array<float, 16> Camera::projection_matrix(float aspect) const {
  // Near / far from the distance: the scene is a fabric of a few times the distance at most.
  const float n = distance_m * 0.02f, f = distance_m * 20.0f;
  const float t = 1.0f / std::tan(0.5f * fov_y_deg * kDegToRad);
  return {t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (f + n) / (n - f), -1, 0, 0, 2 * f * n / (n - f), 0};
}

std::array<float, 16> Camera::view_projection(float aspect) const {
  return mul(projection_matrix(aspect), view_matrix());
}

bool Camera::project(const Vec3& world, float aspect, float* u, float* v) const {
  const auto clip = mul(view_projection(aspect), std::array<float, 4>{world[0], world[1], world[2], 1.0f});
  if (clip[3] <= 0) return false;
  *u = 0.5f * (clip[0] / clip[3] + 1.0f);
  *v = 0.5f * (1.0f - clip[1] / clip[3]);
  return true;
}

void Camera::fit_box(const Vec3& lo, const Vec3& hi, float aspect, float margin) {
  target = (lo + hi) * 0.5f;
  const Vec3 w = eye_direction(yaw_deg, pitch_deg), r = right(), u = up();
  const float ty = std::tan(0.5f * fov_y_deg * kDegToRad) / margin;
  const float tx = ty * aspect;
  // Each corner c (relative to the target) needs |c.r| <= (d - c.w) tan(half fov x), the
  // same for u with the vertical half angle: the smallest d that satisfies all 8 corners.
  float d = 1e-4f;
  for (int i = 0; i < 8; ++i) {
    const Vec3 c = Vec3{(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]} - target;
    d = std::max(d, dot(c, w) + std::abs(dot(c, r)) / tx);
    d = std::max(d, dot(c, w) + std::abs(dot(c, u)) / ty);
  }
  distance_m = d;
}

void Camera::fit(const Frame& frame, float aspect, float margin) {
  // The whole fabric's plan is known from the frame; its z extent comes from the nodes.
  float zlo = 0, zhi = 0;
  for (const auto& p : frame.node_pos) {
    zlo = std::min(zlo, p[2]);
    zhi = std::max(zhi, p[2]);
  }
  // Nodes flung far away after a perforation should not shrink the fabric to a dot.
  const float zcap = std::max(frame.half_width_m, frame.half_length_m);
  zlo = std::max(zlo, -zcap);
  zhi = std::min(zhi, zcap);
  fit_box({-frame.half_width_m, -frame.half_length_m, zlo}, {frame.half_width_m, frame.half_length_m, zhi}, aspect,
          margin);
}

Camera fitted_camera(const Frame& frame, ViewPreset view, float aspect) {
  Camera c = Camera::preset(view);
  if (view != ViewPreset::section) {
    c.fit(frame, aspect, 1.06f);
    return c;
  }
  // Section: fit the cut (the x-z profile through the impact point), not the whole plan.
  float zlo = 0, zhi = 0;
  const float zcap = std::max(frame.half_width_m, frame.half_length_m);
  for (const auto& p : frame.node_pos) {
    zlo = std::min(zlo, std::max(p[2], -zcap));
    zhi = std::max(zhi, std::min(p[2], zcap));
  }
  const float y = frame.projectile_pos[1];
  c.fit_box({-frame.half_width_m, y, zlo}, {frame.half_width_m, y, zhi}, aspect, 1.08f);
  return c;
}

}  // namespace ravel::render

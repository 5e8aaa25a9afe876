#include "render/picking.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ravel::render {

std::vector<std::array<float, 3>> view_copies(const Frame& frame, const ViewOptions& o) {
  std::vector<std::array<float, 3>> copies = {{1, 1, 1}};
  if (o.mirror && frame.mirror_x) copies.push_back({-1, 1, 1});
  if (o.mirror && frame.mirror_y) {
    const std::size_t n = copies.size();
    for (std::size_t i = 0; i < n; ++i) copies.push_back({copies[i][0], -1, 1});
  }
  return copies;
}

namespace {

struct Projected {
  bool ok = false;
  float x = 0, y = 0, depth = 0;
};

Projected project(const Camera& cam, const std::array<float, 3>& p, const std::array<float, 3>& m, float aspect, int w,
                  int h, const Vec3& eye) {
  const Vec3 world{p[0] * m[0], p[1] * m[1], p[2] * m[2]};
  Projected r;
  float u = 0, v = 0;
  if (!cam.project(world, aspect, &u, &v)) return r;
  r.ok = true;
  r.x = u * float(w);
  r.y = v * float(h);
  const Vec3 d{world[0] - eye[0], world[1] - eye[1], world[2] - eye[2]};
  r.depth = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  return r;
}

// Distance from (px, py) to segment ab in pixels, and where along it (0..1).
float segment_distance(float px, float py, const Projected& a, const Projected& b, float* t_out) {
  const float dx = b.x - a.x, dy = b.y - a.y;
  const float len2 = dx * dx + dy * dy;
  float t = len2 > 0 ? ((px - a.x) * dx + (py - a.y) * dy) / len2 : 0.0f;
  t = std::clamp(t, 0.0f, 1.0f);
  const float qx = a.x + t * dx - px, qy = a.y + t * dy - py;
  *t_out = t;
  return std::sqrt(qx * qx + qy * qy);
}

// A candidate d pixels from the point and `depth` from the eye beats the best so far if it is
// clearly nearer on screen, or equally near (within a pixel) and nearer the eye.
bool nearer(float d, float depth, float* best_d, float* best_depth) {
  if (!(d < *best_d - 1.0f || (d <= *best_d + 1.0f && depth < *best_depth))) return false;
  *best_d = std::min(*best_d, d);
  *best_depth = depth;
  return true;
}

bool cut_away(const Frame& frame, const ViewOptions& o, const std::array<float, 3>& p, const std::array<float, 3>& m) {
  const bool cut = o.section_cut || o.view == ViewPreset::section;
  return cut && p[1] * m[1] < frame.projectile_pos[1];
}

}  // namespace

Pick pick_element(const Frame& frame, const Camera& camera, const ViewOptions& o, int w, int h, float x_px, float y_px,
                  float max_px) {
  Pick best;
  if (w <= 0 || h <= 0) return best;
  const float aspect = float(w) / float(h);
  const Vec3 eye = camera.eye();
  const auto copies = view_copies(frame, o);
  const std::size_t ne = std::min(frame.elem_a.size(), frame.elem_b.size()), np = frame.node_pos.size();
  float best_d = max_px, best_depth = std::numeric_limits<float>::max();
  std::vector<Projected> proj(np);
  for (std::size_t c = 0; c < copies.size(); ++c) {
    const auto& m = copies[c];
    for (std::size_t i = 0; i < np; ++i) proj[i] = project(camera, frame.node_pos[i], m, aspect, w, h, eye);
    for (std::size_t e = 0; e < ne; ++e) {
      if (e < frame.elem_broken.size() && frame.elem_broken[e]) continue;
      const std::uint32_t a = frame.elem_a[e], b = frame.elem_b[e];
      if (a >= np || b >= np || !proj[a].ok || !proj[b].ok) continue;
      if (cut_away(frame, o, frame.node_pos[a], m) && cut_away(frame, o, frame.node_pos[b], m)) continue;
      float t = 0;
      const float d = segment_distance(x_px, y_px, proj[a], proj[b], &t);
      if (d > max_px) continue;
      const float depth = proj[a].depth + t * (proj[b].depth - proj[a].depth);
      if (nearer(d, depth, &best_d, &best_depth)) {
        best = Pick{};
        best.element = int(e);
        best.copy = int(c);
        best.mirror = m;
        best.distance_px = d;
      }
    }
  }
  return best;
}

Pick pick_crossing(const Frame& frame, const Camera& camera, const ViewOptions& o, int w, int h, float x_px, float y_px,
                   float max_px) {
  Pick best;
  if (w <= 0 || h <= 0) return best;
  const float aspect = float(w) / float(h);
  const Vec3 eye = camera.eye();
  const auto copies = view_copies(frame, o);
  const std::size_t nc = std::min(frame.crossing_warp_node.size(), frame.crossing_weft_node.size());
  const std::size_t np = frame.node_pos.size();
  float best_d = max_px, best_depth = std::numeric_limits<float>::max();
  for (std::size_t c = 0; c < copies.size(); ++c)
    for (std::size_t k = 0; k < nc; ++k) {
      if (k < frame.crossing_active.size() && !frame.crossing_active[k]) continue;
      const std::uint32_t a = frame.crossing_warp_node[k], b = frame.crossing_weft_node[k];
      if (a >= np || b >= np) continue;
      const auto& pa = frame.node_pos[a];
      const auto& pb = frame.node_pos[b];
      const std::array<float, 3> mid{0.5f * (pa[0] + pb[0]), 0.5f * (pa[1] + pb[1]), 0.5f * (pa[2] + pb[2])};
      if (cut_away(frame, o, mid, copies[c])) continue;
      const Projected q = project(camera, mid, copies[c], aspect, w, h, eye);
      if (!q.ok) continue;
      const float d = std::hypot(q.x - x_px, q.y - y_px);
      if (d > max_px) continue;
      if (nearer(d, q.depth, &best_d, &best_depth)) {
        best = Pick{};
        best.crossing = int(k);
        best.copy = int(c);
        best.mirror = copies[c];
        best.distance_px = d;
      }
    }
  return best;
}

}  // namespace ravel::render

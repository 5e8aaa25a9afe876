// Synthetic Frames for render tests and the render benchmark: a quarter of a plain-weave
// fabric (crossing warp / weft yarns with crimp), optionally dented into a cone under the
// projectile, strained near the impact point and with a hole of broken elements.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/frame.h"

namespace ravel::testing {

struct SyntheticFabric {
  int yarns = 72;               // per family in the modelled quarter
  float spacing_m = 0.844e-3f;  // L0
  float gap_m = 0.2e-3f;        // L1
  float dent_depth_m = 0.0f;    // cone depth at the impact point
  float dent_radius_m = 0.03f;
  float peak_strain = 0.0f;  // fraction of failure strain at the impact point
  float strain_decay_m = 0.015f;
  float hole_radius_m = 0.0f;  // elements with a node inside are broken
  float projectile_z_m = 0.01f;
  bool quarter = true;  // mirror_x / mirror_y
  double time_s = 20e-6;
  bool perforated = false;
};

inline Frame make_synthetic_frame(const SyntheticFabric& s) {
  Frame f;
  f.scene_name = "synthetic";
  f.model_label = s.quarter ? "quarter, sliding" : "full, sliding";
  f.time_s = s.time_s;
  f.friction = 0.2;
  f.impact_velocity_mps = 260;
  f.perforated = s.perforated;
  f.failure_strain = 0.052f;
  f.yarn_diameter_m = 0.2e-3f;
  const int n = s.yarns;
  // Quarter: yarn 0 lies on the symmetry plane. Full: yarns centred on the origin.
  const float origin = s.quarter ? 0.0f : -0.5f * (n - 1) * s.spacing_m;
  f.half_width_m = f.half_length_m = s.quarter ? (n - 1) * s.spacing_m : 0.5f * (n - 1) * s.spacing_m;
  f.mirror_x = f.mirror_y = s.quarter;

  auto dent = [&](float x, float y) {
    const float r = std::max(std::abs(x), std::abs(y));  // pyramid, as woven fabric deforms
    return -s.dent_depth_m * std::max(0.0f, 1.0f - r / s.dent_radius_m);
  };
  auto strain_at = [&](float x, float y) {
    const float r = std::hypot(x, y);
    return s.peak_strain * f.failure_strain * std::exp(-r / s.strain_decay_m);
  };
  // Node (i, j) of family k: warp nodes first, then weft nodes.
  auto node = [&](int k, int i, int j) { return static_cast<std::uint32_t>(k * n * n + i * n + j); };
  f.node_pos.resize(2 * n * n);
  f.node_vel.resize(2 * n * n);
  f.node_slip_rate.resize(2 * n * n);
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const float x = origin + i * s.spacing_m, y = origin + j * s.spacing_m;
        const float crimp = ((i + j + k) % 2 ? 0.5f : -0.5f) * s.gap_m;
        const float z = dent(x, y) + crimp;
        f.node_pos[node(k, i, j)] = {x, y, z};
        const float speed = s.dent_depth_m > 0 ? 200.0f * dent(x, y) / -s.dent_depth_m : 0.0f;
        f.node_vel[node(k, i, j)] = {0, 0, -speed};
        f.node_slip_rate[node(k, i, j)] = 0.2f * speed * std::exp(-std::hypot(x, y) / 0.01f);
      }
  auto add = [&](std::uint32_t a, std::uint32_t b, int family, std::uint32_t yarn) {
    const auto& pa = f.node_pos[a];
    const auto& pb = f.node_pos[b];
    const float mx = 0.5f * (pa[0] + pb[0]), my = 0.5f * (pa[1] + pb[1]);
    f.elem_a.push_back(a);
    f.elem_b.push_back(b);
    f.elem_family.push_back(static_cast<std::uint8_t>(family));
    const bool broken = std::hypot(pa[0], pa[1]) < s.hole_radius_m || std::hypot(pb[0], pb[1]) < s.hole_radius_m;
    f.elem_broken.push_back(broken ? 1 : 0);
    f.elem_yarn.push_back(yarn);
    const float e = strain_at(mx, my);
    f.elem_strain.push_back(e);
    f.elem_stress_pa.push_back(7.28e10f * e);
  };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      add(node(0, i, j), node(0, i, j + 1), 0, i);      // warp i runs along y
      add(node(1, j, i), node(1, j + 1, i), 1, n + i);  // weft i runs along x
    }
  f.projectile_shape = 0;
  f.projectile_radius_m = 6e-3f;
  f.projectile_pos = {0, 0, s.projectile_z_m};
  return f;
}

}  // namespace ravel::testing

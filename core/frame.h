// Frame: a frozen copy of what a viewer needs to draw one instant of a run.
//
// The renderer and the app only ever see Frames, never the solver's live arrays: the
// worker thread copies one out under a short lock (Simulation::frame()), the UI draws it
// at leisure. Everything is in metres / seconds / SI, single precision is plenty here.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace ravel {

struct Frame {
  // Caption data.
  std::string scene_name;
  std::string model_label;  // e.g. "quarter, sliding"
  double time_s = 0.0;
  double friction = 0.0;  // yarn-yarn mu
  double impact_velocity_mps = 0.0;
  bool perforated = false;

  // Modelled nodes (a quarter, a half or the full fabric; see mirror_x/mirror_y).
  std::vector<std::array<float, 3>> node_pos;  // m
  std::vector<std::array<float, 3>> node_vel;  // m/s
  std::vector<float> node_slip_rate;           // m/s, sliding speed at the node's crossing (0 when stuck / pin-jointed)
  // J/g: the yarn-yarn friction's heat so far (Solver::crossing_friction_heat), each
  // crossing's half at each yarn's node where the contact is now, per gram of the two nodes
  // (the same on a symmetry plane, where heat and mass are both halved). About 1.42 J/g per
  // kelvin for aramid.
  std::vector<float> node_friction_j_per_g;

  // Yarn elements: straight two-node segments.
  std::vector<std::uint32_t> elem_a, elem_b;  // node indices
  std::vector<std::uint8_t> elem_family;      // 0 = warp (runs along y), 1 = weft (runs along x)
  std::vector<std::uint8_t> elem_broken;      // 1 = failed and removed
  std::vector<std::uint32_t> elem_yarn;       // yarn id (0.. warp count-1 are warp, then weft)
  // Per modelled yarn: its grid index (warp: I, at x = I L0; weft: J, at y = J L0) and family;
  // what makes yarn ids unique across the mirrored copies (write_vtu).
  std::vector<std::int32_t> yarn_grid;
  std::vector<std::uint8_t> yarn_family;
  std::vector<float> elem_strain;     // engineering strain
  std::vector<float> elem_stress_pa;  // axial stress

  // Yarn-yarn crossings of the sliding model (empty for the pin-jointed model): the node
  // each yarn's contact is tracked at, the crossing's grid indices (I along x, J along y),
  // the normal force of the last step (N, this modelled crossing: half or a quarter of a
  // real one on a symmetry plane), its slip rate (m/s) and whether it is still a contact
  // (released crossings: ravelled out, passed through, inside a clamp).
  std::vector<std::uint32_t> crossing_warp_node, crossing_weft_node;
  std::vector<std::int32_t> crossing_i, crossing_j;
  std::vector<float> crossing_normal_force_n, crossing_slip_rate;
  std::vector<std::uint8_t> crossing_active;
  float failure_strain = 0.052f;
  float yarn_diameter_m = 0.2e-3f;  // drawn tube diameter (contact diameter D)

  // Symmetry: the modelled part is mirrored across x = 0 and/or y = 0 to show the whole fabric.
  bool mirror_x = false, mirror_y = false;
  float half_width_m = 0.06f, half_length_m = 0.06f;
  bool clamped_left = true, clamped_right = true, clamped_bottom = false, clamped_top = false;

  // Projectile (rigid body): shape 0 sphere, 1 flat-faced cylinder, 2 cone.
  int projectile_shape = 0;
  std::array<float, 3> projectile_pos{0, 0, 0};
  std::array<float, 3> projectile_axis{0, 0, -1};  // direction of flight at impact
  float projectile_radius_m = 6e-3f;
  float projectile_length_m = 12e-3f;
};

}  // namespace ravel

// Model: everything about a run that does not change while it runs (MuJoCo's mjModel):
// topology of the yarn network, rest lengths, masses, material constants, crossing
// signs, clamps, symmetry planes, the projectile's shape and mass, the time step.
//
// Coordinates: the fabric lies in the x-y plane centred on the origin, z up. Warp yarns
// run along y (one per x position I*L0), weft yarns run along x (one per y position
// J*L0). The projectile starts above (+z) and flies towards -z. At crossing (I, J) the
// warp yarn is on top when I + J is even (plain-weave crimp), so the centre crossing
// has the warp on top.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "scene.h"
#include "shape.h"

namespace ravel {

using Vec3d = Eigen::Vector3d;

enum Family : std::uint8_t { warp = 0, weft = 1 };

// Bits of Model::fixed: which velocity components of a node are held at zero.
enum FixedAxis : std::uint8_t { fix_x = 1, fix_y = 2, fix_z = 4, fix_all = 7 };

struct Crossing {
  int warp_yarn = 0, weft_yarn = 0;  // yarn ids
  int warp_node = 0, weft_node = 0;  // initial nearest node, as position along each yarn
  int grid_i = 0, grid_j = 0;        // global crossing indices I, J
  double side = 1.0;                 // n = side * normalize(t_warp x t_weft) points warp -> weft
  double contact_distance = 0.0;     // D used at this crossing (min of D and the rest distance): c0
  // Compression (hyperbolic law): the distance of fully flattened yarns (c_min <= c0; = c0
  // when rigid) and the force F_half of this modelled crossing (the scene's per real
  // crossing, times the real crossings it stands for: k^2 when lumped, halved on each
  // symmetry plane it lies on).
  double flattened_distance = 0.0;
  double compression_force = 0.0;
  // The two-stage law's packed distance c_pack (c_min <= c_pack <= c0; = c_min: one stage) and
  // the flattening stage's force F_flat (scaled like compression_force).
  double packed_distance = 0.0;
  double flattening_force = 0.0;
};

struct Model {
  // --- what was asked and what was built
  std::string symmetry_label;   // quarter | half | full
  std::string symmetry_reason;  // in words
  ContactModel contact = ContactModel::sliding;
  bool mirror_x = false, mirror_y = false;  // modelled part is x >= 0 / y >= 0
  double symmetry_factor = 1.0;             // whole-fabric quantity = modelled x factor

  // --- nodes
  int node_count = 0;
  std::vector<Vec3d> x0;            // initial positions (m)
  std::vector<double> mass;         // kg (half / quarter on symmetry planes)
  std::vector<double> inv_mass;     // 1/kg, 0 for clamped nodes
  std::vector<std::uint8_t> fixed;  // FixedAxis bits
  // Slipping clamps (fabric.clamp = slipping, docs/MODEL.md §7): the clamp feeds yarn into
  // the element that ends in it (`element`, its clamped end `node` stays where it is) while
  // the element pulls harder than the grip `force` (N, the modelled yarn's): the element's
  // rest length grows by the yarn paid out (State::grip_payout), a rigid-plastic slider.
  struct Grip {
    int element = 0, node = 0;
    double force = 0;
  };
  std::vector<Grip> grips;
  double clamp_depth = 0;         // m: yarn a clamp can feed before the yarn has left it
  std::vector<int> grip_of_elem;  // per element: index into grips, -1 none (empty: no slipping clamp)

  // --- yarns: yarn y owns nodes yarn_nodes[yarn_offset[y] .. yarn_offset[y+1])
  int warp_count = 0, weft_count = 0;  // modelled yarns; warp ids first, then weft
  std::vector<int> yarn_offset, yarn_nodes;
  std::vector<std::uint8_t> yarn_family;
  std::vector<int> yarn_grid;               // global index I (warp) or J (weft)
  std::vector<int> yarn_elem_offset;        // element k of yarn y is yarn_elem_offset[y] + k
  std::vector<std::uint8_t> yarn_end_free;  // bit 0: first node is a free end, bit 1: last node
  std::vector<std::int8_t>
      yarn_start_mirror;  // first node on the mirror plane x = 0 (0) / y = 0 (1) the yarn crosses; -1 none

  int yarn_count() const { return int(yarn_family.size()); }
  int yarn_size(int y) const { return yarn_offset[y + 1] - yarn_offset[y]; }
  int yarn_node(int y, int k) const { return yarn_nodes[yarn_offset[y] + k]; }

  // --- elements (straight two-node yarn segments, tension only)
  int element_count = 0;
  std::vector<int> elem_a, elem_b, elem_yarn;
  std::vector<double> elem_rest;  // initial length, m: the crimped zig-zag's (sliding), the node spacing (pin-jointed)
  std::vector<double> elem_area;  // m^2 (half for a yarn on a symmetry plane, x k when lumped)

  // --- pin-jointed crimp stage (docs/MODEL.md §1): an element's apparent strain e = len / L0 - 1
  // takes up the crimp e_c = sqrt(L0^2 + L1^2) / L0 - 1 in a toe whose stiffness rises from
  // crimp_fraction (r) of the modulus to all of it over [0, 2 crimp_width], crimp_width = e_c
  // (crimp_stage in core/solver/stage.h). crimp_strain = 0: no crimp stage (sliding and single-yarn models).
  double crimp_strain = 0, crimp_fraction = 0, crimp_width = 0;
  double crimp_damping_beta = 0;  // s: beta of the pin-jointed stretch damping (yarn.crimp_damping x L / c)

  // --- bending: compression-only springs between midpoints of adjoining elements.
  // bend_mirror >= 0 marks the spring that, in the full fabric, joins a yarn's first
  // modelled element to its mirror image across plane x = 0 (0) or y = 0 (1); e2 == e1.
  std::vector<int> bend_e1, bend_e2, bend_mirror;
  std::vector<double> bend_k, bend_rest;

  // --- yarn-yarn crossings (sliding model only)
  std::vector<Crossing> crossings;
  double friction = 0.2;
  double friction_penalty = 0.25;
  bool split_penetration = true;
  bool projectile_holds = true;
  int contact_iterations = 1;
  CrossingCompression compression = CrossingCompression::rigid;

  // --- material
  Material material = Material::zener;
  double k1 = 0, k2 = 0, damping = 0;  // Zener constants, Pa / Pa s
  double modulus_inst = 0;             // K1 (zener) or E (elastic)
  double density = 0;
  double failure_strain = 0.052;
  bool breakable = true;

  // --- projectile (rigid)
  Shape shape;
  double projectile_mass = 0;       // modelled (M / symmetry_factor)
  double projectile_mass_full = 0;  // M
  double impact_velocity = 0;       // V0, m/s
  Vec3d flight_dir{0, 0, -1};       // unit direction of flight
  Vec3d projectile_x0{0, 0, 0};
  double projectile_friction = 0.27;

  // --- time
  double dt = 0;          // s
  double wave_speed = 0;  // sqrt(E_inst / rho)
  double shortest_element = 0;
  double critical_dt_factor = 1.0;  // estimate of the alpha at which central differences go unstable
  // The same with a node held on the projectile (an effective stiffness m / dt^2 from the
  // push-out, docs/MODEL.md §3): sqrt(3)/2 of critical_dt_factor when the projectile holds
  // nodes, which long runs near the ballistic limit meet.
  double held_dt_factor = 1.0;
  double element_damping_beta = 0;  // s: beta of the snap damping (solver.snap_damping x L / c)
  double end_time = 0;

  // --- fabric extent (whole fabric)
  double half_width = 0, half_length = 0;
  ClampedEdges clamped;
  double thickness = 0;

  // Initial energy of the whole system (the projectile's kinetic energy), J, whole fabric.
  double initial_energy() const { return 0.5 * projectile_mass_full * impact_velocity * impact_velocity; }
};

// Build the model a scene asks for, choosing the smallest symmetric part when
// scene.solver.symmetry is auto.
// The mirror planes a scene allows (SPEC §6) and, in words, why not the others.
struct SymmetryChoice {
  bool mirror_x = false, mirror_y = false;
  std::string why_not;
};
SymmetryChoice choose_symmetry(const Scene& scene);

Model build_model(const Scene& scene);

}  // namespace ravel

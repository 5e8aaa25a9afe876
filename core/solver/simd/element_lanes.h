// The yarn elements' strain, Zener stress update and force (Eq 3, 23; docs/MODEL.md §2) for
// four elements at once, in the AVX2 lanes of processors that have them.
//
// As in contact_lanes.h, the lane code performs lane by lane exactly the IEEE operations of
// the one-element code in solver/internal_forces.cpp (InternalForces::element_one with ZenerStepper::step), in
// the same order, without floating-point contraction: the results are the same bit for bit
// (tested). It covers the regular case, four intact elements of which none fails in this
// step; the solver does the others one at a time. With the pin-jointed model's crimp stage
// the strain the yarn law sees and the force factor are the crimp stage's, lane by lane.
#pragma once

#include "contact_lanes.h"

namespace ravel::lanes {

struct ElementBatch {
  // In: node positions (x y z per node), the four elements' end nodes, rest lengths and
  // cross-sections; the Zener stepper's constants (ZenerStepper); the failure strain.
  const double* x;
  const int *a, *b;  // at element e0 of the model's arrays, as the next four
  const double *rest, *area;
  double k1, k2, mu, dt, inv_dt, lam, g, decay, slack_decay;
  double fail;
  bool breakable;
  double damping_k = 0;  // beta E_inst of the element damping (internal_forces.cpp: element_one)
  // The pin-jointed crimp stage (stage.h: crimp_stage; crimp_strain 0: none) and its damping
  // (yarn.crimp_damping: crimp_damping_k = beta E A / A, crimp_damp_stress per element, in/out).
  double crimp_strain = 0, crimp_fraction = 1, crimp_width = 0;
  double crimp_damping_k = 0;
  double* crimp_damp_stress = nullptr;
  // In/out, per element (pointers to element e0 of the solver's arrays): last step's strain
  // (becomes this step's), the viscous strain; out: strain, stress, stored energy and the
  // force on node b (x y z per element).
  double *prev_strain, *ev, *strain, *stress, *energy, *force;
  // Out (optional): the elements' midpoints, 0.5 (x_a + x_b), for the bending springs (bend4):
  // x, y and z in three blocks `mid_stride` apart, at element e0 (null: not wanted).
  double* mid = nullptr;
  int mid_stride = 0;
  // Out, per lane, for the solver's sums (taken in element order): stored energy, energy
  // dissipated by the dashpot over the step, strain.
  // (dw: the snap damping's work; cw: the crimp damping's, added after it as element_one does)
  double u[kWidth], dd[kWidth], eps[kWidth], dw[kWidth], cw[kWidth];
};

// Four bending springs (internal_forces.cpp: the compression-only springs between the
// midpoints of adjoining elements), none of them broken or on a symmetry plane.
struct BendBatch {
  // In: node positions; per lane the end nodes of the spring's two elements; the springs'
  // rest distances and stiffnesses (pointers to spring s0 of the model's arrays, as the next four).
  const double* x;
  int a1[kWidth], b1[kWidth], a2[kWidth], b2[kWidth];
  // Or, for four springs between consecutive elements e1 .. e1 + 4 of one yarn (spring l
  // joins e1 + l and e1 + l + 1), the midpoints zener4 / element_one kept this step (blocks
  // as ElementBatch::mid; null: from the node positions, through a1 .. b2).
  const double* mid = nullptr;
  int mid_stride = 0, e1 = 0;
  const double *rest, *k;
  // Out: the force on the second midpoint (x y z per spring) and the stored energy, per
  // spring (pointers to spring s0 of the solver's arrays), and the energies in lane order.
  double *force, *energy;
  double held[kWidth];
};

// The gather of the element and bending-spring forces into each node's force, and the free
// update of Eq 1-2 (internal_forces.cpp; stage.h: free_update), for the nodes [lo, hi): one
// node at a time with its x y z in three lanes of a vector, the same IEEE operations in the
// same order as the one-node code (its squared distance from the centre summed (x + y) + z).
struct NodeForces {
  // In, CSR (Context::inc_e_off / inc_e, inc_b_off / inc_b): a node's elements, e where it
  // is the element's b (+F) and ~e where it is its a (-F); its spring ends as (spring, weight)
  // pairs of an int and a double, 16 bytes each. Element and spring forces, 3 doubles each.
  const int *inc_e_off, *inc_e, *inc_b_off;
  const char* inc_b;
  const double *elem_force, *bend_force;
  const double* inv_mass;
  const unsigned char* fixed;  // FixedAxis bits
  double dt;
  // Out: node forces (3 doubles a node); in/out: velocities, positions; out: v(t - dt/2)
  // kept in v_prev, and each node's dx_contact cleared (State::Corrections, 12 doubles a node,
  // dx_contact the last three).
  double *f, *v, *x, *v_prev, *corr;
  int lo, hi;
};
// Returns std::max, node by node in order from max_r2, of each node's |x|^2 after the update
// (0 for a node fixed on every axis). Only call when available().
double gather_forces(const NodeForces& s, double max_r2);

// Updates the four springs (always succeeds). Only call when available().
void bend4(BendBatch& s);

// Updates the four elements and returns true, or returns false without writing anything
// when one of them reaches the failure strain (the solver then does them one at a time).
// Only call when available().
bool zener4(ElementBatch& s);

namespace avx2 {
bool zener4(ElementBatch& s);
void bend4(BendBatch& s);
double gather_forces(const NodeForces& s, double max_r2);
}  // namespace avx2
namespace avx512 {
bool zener4(ElementBatch& s);
void bend4(BendBatch& s);
double gather_forces(const NodeForces& s, double max_r2);
}  // namespace avx512

}  // namespace ravel::lanes

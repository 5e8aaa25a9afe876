// What the stages of a step share: the Context (what the model and the options determine,
// and the per-step scratch), the helpers more than one stage uses, and the stages themselves.
//
// A stage is a free function of (model, state, run, context), like MuJoCo's mj_fwdPosition
// (m, d): the Model (core/model.h) does not change during a run, State (state.h) and RunState
// (solver.h) are the run's dynamic state as plain data, and the Context holds what the model
// and the options determine (incidence lists, material constants, thread count) plus scratch
// a stage needs within a step and forgets. Each stage file keeps its helpers in a file-local
// struct bound to those four, so the compiler inlines them into the hot loops as it did when
// the whole solver was one class in one file.
//
// Private to core/solver/: the rest of ravel sees the Solver interface of solver.h only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "geometry.h"
#include "material.h"
#include "model.h"
#include "solver.h"
#include "solver/simd/contact_lanes.h"
#include "solver/state.h"

#ifdef _OPENMP
#include <omp.h>
#endif

// The per-crossing helpers the stages call in their hot loops are inlined into them (left to
// its heuristics, GCC kept some out of line, and the default scene's step was 3.5 % slower).
#define RAVEL_INLINE [[gnu::always_inline]] inline

namespace ravel::detail {

// The yarn contact's sums over one thread's share of the crossings at the end of a step (a
// cache line each, so that the threads do not share one).
struct alignas(64) ContactTally {
  double fn = 0, comp_u = 0, stick_e = 0;  // normal force, compression energy, stick-spring energy
  int sliding = 0, stuck = 0;              // loaded crossings that slide / stick
  bool events = false;                     // some crossing has an event to book
};

// The ledger's sums over one thread's share of the nodes at the end of a step (finish_step:
// kinetic energy of v(t + dt/2) and the work of the contact's corrections), a cache line each.
struct alignas(64) NodeBook {
  double ke = 0, w_contact = 0, w_friction = 0, w_compress = 0;
};

// One crossing's corrections for one pass of the yarn contact, computed from the same state for
// every crossing (Jacobi) and applied afterwards in a fixed order: the result does not depend
// on the order crossings are visited in, nor on the number of threads.
template <class Real>
struct CrossingImpulse {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  int node[6];   // warp kw-1..kw+1, weft kf-1..kf+1 (-1: none)
  Real w[6];     // signed weights: -warp, +weft
  V3 P;          // normal impulse on the weft contact point (Eq 9-11)
  V3 S;          // position shift (mass-weighted, like P) of penetration left from before the step
  int fnode[4];  // friction: warp pair, weft pair
  Real fw[4];
  V3 F;  // friction impulse on the weft contact point (Eq 15)
  V3 C;  // compression: the impulse of the crossing's transverse-compression law (same weights as P)
  bool has_n, has_f, has_s, has_c;
  bool any_held;  // a window node is held by the projectile (set by pass_normal)
  bool hold;      // nodes the projectile holds do not yield into it (release_held)
};

template <class Real>
struct Context {
  // --- What the model and the options determine (made by make_context, not written).
  int threads = 1;
  bool simd = false;  // lanes in use (contact_lanes.h, element_lanes.h): asked for, double, the processor has them
  ZenerStepper zener;
  bool compressible = false;  // crossings have a transverse-compression law
  // Node -> element and node -> bending spring, in CSR form:
  std::vector<int> inc_e_off, inc_b_off;
  // node -> element: e where the node is the element's b (its force +F), ~e where it is its a
  // (-F); node -> (bending spring, weight +-1/2, or 1/2 for a mirror spring).
  std::vector<int> inc_e;
  std::vector<std::pair<int, Real>> inc_b;
  // Per group of kBatch bending springs (internal_forces): 1 when its springs join consecutive
  // elements e1 .. e1 + kBatch of one yarn, none on a symmetry plane, and elem_mid is kept (below).
  std::vector<std::uint8_t> bend_along;
  double escape_radius2 = 1;   // a node farther than this (squared) from the centre has escaped
  double damping_k = 0;        // beta E_inst of the snap damping (solver.snap_damping)
  double crimp_damping_k = 0;  // the same for yarn.crimp_damping

  // --- Per-step scratch: what a stage needs within a step and forgets.
  // Per element, its midpoint this step (x, y, z in three blocks of element_count; double
  // precision with lanes only): written by the element stage, read by the bending lanes.
  std::vector<double> elem_mid;
  std::vector<int> near;                       // projectile_contact: nodes in its bounding box
  std::vector<std::vector<int>> near_part;     // the same, per thread
  std::vector<int> rec_first, rec_last;        // yarn_contact: node bounds of the pass's records, running
  std::vector<int> chunk_first, chunk_last;    // the same bounds at the ends of each thread's crossings
  std::vector<int> batch_bound;                // yarn_contact: the crossing batches thread t takes, [t, t + 1)
  std::vector<double> batch_busy;              // and the seconds each thread spent on them this step
  std::vector<Real> moved;                     // yarn_contact: per crossing, the yarns' relative move this step
  std::vector<ContactTally> tally;             // yarn_contact: the step's sums, per thread
  std::vector<NodeBook> node_book;             // yarn_contact's last pass: the ledger's node sums, per thread
  std::vector<std::vector<int>> shifted_part;  // and the nodes it shifted this step, per thread (node order)
  std::vector<CrossingImpulse<Real>> impulses;
  double max_r2 = 0;  // internal_forces' free update: the largest squared distance of a node from the centre

  explicit Context(const Model& m);
};

// Whether a Real can run the lanes on this processor (double precision, AVX2 or better).
template <class Real>
bool lanes_possible() {
  return std::is_same_v<Real, double> && lanes::available();
}

// Zero the components of a node's velocity / displacement change along its fixed axes
// (clamps, symmetry planes).
template <class V3>
inline void zero_fixed(V3& v, std::uint8_t fx) {
  if (fx & fix_x) v.x() = 0;
  if (fx & fix_y) v.y() = 0;
  if (fx & fix_z) v.z() = 0;
}

// Inside a parallel region: this thread's number t and the team's size.
inline void my_team(int& t, int& team) {
#ifdef _OPENMP
  t = omp_get_thread_num();
  team = omp_get_num_threads();
#else
  t = 0;
  team = 1;
#endif
}

// Inside a parallel region: this thread's share [lo, hi) of n items (contiguous, in thread
// order) and its number t.
inline void my_share(int n, int& lo, int& hi, int& t) {
  int T;
  my_team(t, T);
  lo = int(long(n) * t / T);
  hi = int(long(n) * (t + 1) / T);
}

// Wall-clock seconds (for load balancing only: never part of a result).
inline double wall_seconds() {
#ifdef _OPENMP
  return omp_get_wtime();
#else
  return 0;
#endif
}

// The pin-jointed crimp stage (Model::crimp_strain): apparent strain e (against the node
// spacing L0) -> the yarn law's strain g(e) = r e + (1 - r) p(e - e_c) and g'(e), with
// p(x) = (x + e_c)^2 / (4 e_c) across [-e_c, e_c], x above, 0 below: a toe whose stiffness
// rises linearly from r times the modulus at e = 0 to the full modulus at e = 2 e_c, after
// which the yarn stretches with g = e - (1 - r) e_c (the toe's own force, r E e_c, stays: it is
// what holds the crimp out). A force-free slack switched elements between slack and taut from
// step to step; a longer, softer toe let the whole ply deflect before the crimp was out and
// tore it off the clamps (docs/MODEL.md §1). `e` is returned as the yarn's own strain
// (1 + e) / (1 + e_c) - 1, which failure and the outputs use: a yarn breaks at its own stretch.
template <class Real>
inline void crimp_stage(const Model& model, Real& e, Real& mat, Real& dg) {
  const double ec = model.crimp_strain, r = model.crimp_fraction, w = model.crimp_width;
  const double x = double(e) - ec;
  double p = 0, dp = 0;
  if (x >= w)
    p = x, dp = 1;
  else if (x > -w)
    p = (x + w) * (x + w) / (4 * w), dp = (x + w) / (2 * w);
  mat = Real(r * double(e) + (1 - r) * p);
  dg = Real(r + (1 - r) * dp);
  e = Real((1 + double(e)) / (1 + ec) - 1);
}

// The offset (weft minus warp) of crossing c's node pair (kw, kf): how far its yarns moved
// against each other (yarn_contact, and the initial state).
template <class Real>
inline Eigen::Matrix<Real, 3, 1> pair_offset(const Model& model, const State<Real>& s, int c, int kw, int kf) {
  const Crossing& cr = model.crossings[c];
  const int nw = model.yarn_size(cr.warp_yarn), nf = model.yarn_size(cr.weft_yarn);
  const int iw = model.yarn_node(cr.warp_yarn, std::clamp(kw, 0, nw - 1));
  const int jf = model.yarn_node(cr.weft_yarn, std::clamp(kf, 0, nf - 1));
  return s.x[jf] - s.x[iw];
}

// Record the fault that stops a run (faults.cpp; Solver::fault calls it too). Only the first
// is kept; the message is "diverged at step N (t = T us): why".
void record_fault(RunState& run, const std::string& cause, const std::string& why);

// faults.cpp: the checks inside the stages. The energy ledger against the impact energy, once
// per step (close_ledger_row); yarn nodes after the free update, non-finite or escaped
// (integrate; max_r2: the largest squared distance from the centre).
template <class Real>
void check_balance(const Model& model, State<Real>& s, RunState& run, double max_balance_error, double total);
void check_positions(RunState& run, double escape_radius2, double max_r2);

// ------------------------------------------------------------------------- the stages
// In the order step() runs them (solver.h says why); each in its own file.

// internal_forces.cpp: element strain -> stress, failure, bending springs, nodal forces (Eq 3, 23-25).
template <class Real>
void internal_forces(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx);

// ledger.cpp: the ledger row at t - dt/2 and the energy-balance check on it (a fault beyond
// max_balance_error: Solver::set_max_balance_error).
template <class Real>
void close_ledger_row(const Model& model, State<Real>& s, RunState& run, double max_balance_error);

// Element e's rest length now: the model's, plus the yarn a slipping clamp has fed into it.
template <class Real>
inline double elem_rest_now(const Model& model, const State<Real>& s, int e) {
  if (model.grip_of_elem.empty() || model.grip_of_elem[e] < 0) return model.elem_rest[e];
  return model.elem_rest[e] + s.grip_payout[size_t(model.grip_of_elem[e])];
}

// Eq 1-2 for node i: v(t+dt/2) = v(t-dt/2) + dt/m f; x(t+dt) = x(t) + dt v(t+dt/2), with f
// the node's force. Fixed velocity components (clamps, symmetry planes) stay zero. Also keeps
// v(t-dt/2) for the ledger and clears the step's contact shift. Returns |x|^2 (fault check).
// Run by internal_forces as it gathers each node's force.
template <class Real>
RAVEL_INLINE double free_update(const Model& model, State<Real>& s, int i, const Eigen::Matrix<Real, 3, 1>& f) {
  s.v_prev[i] = s.v[i];
  s.corr[i].dx_contact.setZero();
  const std::uint8_t fx = model.fixed[i];
  if (fx == fix_all) return 0;
  Eigen::Matrix<Real, 3, 1> v = s.v[i] + (Real(model.dt) * Real(model.inv_mass[i])) * f;
  if (fx) zero_fixed(v, fx);
  s.v[i] = v;
  s.x[i] += Real(model.dt) * v;
  return double(s.x[i].squaredNorm());
}

// integrate.cpp: Eq 1-2, the rest of the free update: external loads on nodes, the
// projectile, and the nodes' positions checked.
template <class Real>
void integrate(const Model& model, State<Real>& s, RunState& run, const Context<Real>& ctx);

// projectile_contact.cpp: Eq 18-22.
template <class Real>
void projectile_contact(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx);

// yarn_contact.cpp: Eq 5-17, N Jacobi passes over the crossings.
template <class Real>
void yarn_contact(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx);

// hold.cpp: the yarn contact's push on nodes the projectile holds, passed to it (hold.h).
template <class Real>
void release_held(const Model& model, State<Real>& s, RunState& run);

// yarn_contact.cpp: the interpenetration left at the end of a step (sampled every
// kPenetrationCheckEvery steps).
constexpr int kPenetrationCheckEvery = 8;
template <class Real>
void residual_penetration(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx);

// ledger.cpp: kinetic energy of the half-step velocities and the work of this step's corrections.
template <class Real>
void finish_step(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx);

// faults.cpp: every kProjectileCheckEvery steps, a projectile gone non-finite or out of the domain.
constexpr int kProjectileCheckEvery = 16;
template <class Real>
void check_projectile(const Model& model, const State<Real>& s, RunState& run);

// ledger.cpp: the fabric's kinetic energy (for a projectile velocity set from outside).
template <class Real>
double fabric_ke(const Model& model, const State<Real>& s);

// setup.cpp: the initial state of a model.
template <class Real>
State<Real> initial_state(const Model& model, const Context<Real>& ctx, RunState& run);

}  // namespace ravel::detail

// State<Real>: the dynamic state of a run as plain data (like MuJoCo's mjData beside mjModel):
// every array and scalar one step carries to the next. The Model (core/model.h) is what does
// not change during a run; what the model determines (incidence lists, material constants)
// and the per-step scratch live in the solver, not here.
//
// A State can be copied (it is a value), hashed (hash: the bytes the state-hash probe
// covers) and written and read (io, with core/state_io.h's StateWriter / StateReader): the
// checkpoints of `ravel run --resume` are built on it. Together with the precision-independent
// RunState of solver.h (time, step count, ledger, diagnostics) it is the whole of a run.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "ledger.h"
#include "state_io.h"

namespace ravel::detail {

// The node ids of a crossing's window around its tracked pair: what a window is loaded from.
// Each crossing keeps those of its tracked pair, rebuilt when the pair moves.
struct WindowIds {
  // The tracked pair these are for (none yet).
  int kw = std::numeric_limits<int>::min(), kf = 0;
  int node[6];          // warp kw-1..kw+1, weft kf-1..kf+1 (-1: past a yarn's end)
  int wseg0, fseg0;     // element index of warp segment kw-1 and weft segment kf-1
  std::uint8_t exists;  // bits 0, 1: warp segments kw-1, kw exist; 2, 3: weft kf-1, kf
};

// A crossing's tracked node pair at the end of the last step and the offset between its two
// nodes then (weft minus warp): how far the yarns moved against each other.
template <class Real>
struct LastPair {
  int kw, kf;
  Eigen::Matrix<Real, 3, 1> offset;
};

// One crossing's state: the tracked nearest pair (node index along warp / weft) and its window
// ids, the stick points (-1: none), last step's normal / friction force, slip rate and gap, the
// normal force summed over this step's passes, the compression law's and the stick springs'
// energy at the end of the step, the pair at the end of the last step, and flags.
template <class Real>
struct CrossingState {
  int kw = 0, kf = 0;
  WindowIds win;
  double stick_w = -1, stick_f = -1;
  double fn = 0, ft = 0, slip = 0, gap = 0, fn_step = 0;
  double comp_u = 0, stick_e = 0;
  // The friction's Coulomb dissipation at this crossing so far, the sum of |f_t| v_slip dt
  // (J, this modelled crossing): where friction heats the yarns (Solver::crossing_friction_heat).
  double heat = 0;
  LastPair<Real> last;
  std::uint8_t active = 1, sliding = 0, event = 0;
};

template <class Real>
struct State {
  using V3 = Eigen::Matrix<Real, 3, 1>;

  // --- Nodes (SPEC §1): x(t), v(t - dt/2) (leapfrog), the internal forces of the last
  // internal_forces, and v before this step's integrate (the corrections' work, finish_step).
  std::vector<V3> x, v, f, v_prev;
  // This step's corrections per node and mechanism, side by side (the finish pass adds to all
  // four at once): the velocity changes of the normal contacts (yarn and projectile), of
  // yarn-yarn friction and of the compression law, zeroed by finish_step once booked, and the
  // position shifts, zeroed by integrate.
  struct Corrections {
    V3 dv_contact, dv_friction, dv_compress, dx_contact;
  };
  std::vector<Corrections> corr;
  std::vector<V3> dv_pfriction;     // the projectile's friction (only the nodes it touched: ptouch_list)
  std::vector<double> grip_payout;  // per slipping clamp (Model::grips): yarn fed into its element so far, m
  std::vector<double> grip_heat;    // ... and this step's friction of each (internal_forces; 0 between steps)
  // --- The energy book (core/ledger.h: EnergyBook), and the per-crossing energies summed into it.
  EnergyBook book;
  // (per crossing, in CrossingState below: comp_u, the compression law's stored energy, and
  // stick_e, the stick penalty springs' energy)
  // --- Nodes the projectile pushed out this step: the surface normal (zero: not held), the
  // impulse the yarn contact passed through them to the projectile (with the friction's and
  // the compression's shares), their list, the nodes the projectile touched (their
  // dv_pfriction) and a compact held flag for the hot loops.
  std::vector<V3> held_n, held_imp, held_fric, held_comp;
  std::vector<int> held_list, ptouch_list;
  std::vector<std::uint8_t> held_flag;
  // A pass's corrections summed per node (gather, finish_pass): normal impulse, friction
  // impulse, position shift and compression impulse side by side, so that a crossing's record
  // touches one place per node and the finish pass reads one stream.
  struct PassSum {
    V3 n, f, s, c;
  };
  std::vector<PassSum> pass_sum;
  V3 proj_impulse = V3::Zero();  // the projectile contact's impulse on the projectile this step
  // --- Elements (SPEC §1-2): apparent strain, the yarn law's strain of the last step, the
  // Zener internal strain e_v, stress, broken flags (1: this step, 2: counted), force on
  // node b, stored energy.
  std::vector<Real> strain, prev_strain, ev, stress;
  std::vector<std::uint8_t> broken_flag;
  std::vector<V3> elem_force, bend_force;
  std::vector<double> elem_energy;
  std::vector<double> bend_energy;  // per bending spring: its stored energy at the last step it acted
  // --- Crossings (SPEC §4), one record each (a crossing's step reads and writes most of it).
  std::vector<CrossingState<Real>> cr;
  // --- Projectile (modelled part): position, velocity.
  V3 xp, vp;
  // --- Energy at half steps (solver.h, "Energy timing"): kinetic energy of v(t + dt/2), all
  // and the fabric's; stored energy and the cumulative terms at t and t - dt.
  double ke_half = 0, ke_fabric_half = 0;
  double stored_now = 0, stored_prev = 0, viscous_cum = 0, viscous_prev = 0, released_cum = 0, released_prev = 0;
  double pfriction_cum = 0, contact_cum = 0, external_cum = 0;
  double shift_cum = 0;      // the position shifts' work against the yarn forces (ledger shift_work_J)
  std::vector<int> shifted;  // shift_energy: the nodes shifted this step
  std::vector<unsigned> elem_mark, bend_mark;  // ... and the elements / springs already counted
  unsigned mark = 0;
  std::vector<std::pair<int, V3>> f_ext;                // constant external loads (Solver::set_external_force)
  std::vector<Real> crimp_damp_stress;                  // per element: the crimp damping's stress of the last step
  double balance_window[8] = {0, 0, 0, 0, 0, 0, 0, 0};  // the slow-drift check's memory (check_balance)

  // Every field, in one list for writing and reading (StateWriter / StateReader).
  template <class Ar>
  void io(Ar& ar) {
    ar.mark(0x52565334);  // "RVS4"
    ar.vec(x);
    ar.vec(v);
    ar.vec(f);
    ar.vec(v_prev);
    ar.vec(corr);
    ar.vec(dv_pfriction);
    ar.pod(book);
    ar.vec(held_n);
    ar.vec(held_imp);
    ar.vec(held_fric);
    ar.vec(held_comp);
    ar.vec(held_list);
    ar.vec(ptouch_list);
    ar.vec(held_flag);
    ar.vec(pass_sum);
    ar.pod(proj_impulse);
    ar.vec(strain);
    ar.vec(prev_strain);
    ar.vec(ev);
    ar.vec(stress);
    ar.vec(broken_flag);
    ar.vec(elem_force);
    ar.vec(bend_force);
    ar.vec(bend_energy);
    ar.vec(elem_energy);
    ar.vec(cr);
    ar.pod(xp);
    ar.pod(vp);
    ar.vec(shifted);
    ar.vec(elem_mark);
    ar.vec(bend_mark);
    ar.pod(mark);
    ar.vec(f_ext);
    ar.vec(crimp_damp_stress);
    ar.vec(grip_payout);
    ar.pod(balance_window);
    ar.mark(0x52564532);  // "RVE2"
  }

  // FNV-1a over the bytes of the motion, the internal strains, the broken flags, the stick
  // points and the projectile (what the state-hash probe compares: any change of a number
  // shows in these within a few steps).
  void hash(std::uint64_t& h) const {
    fnv1a(h, x.data(), x.size() * sizeof(V3));
    fnv1a(h, v.data(), v.size() * sizeof(V3));
    fnv1a(h, ev.data(), ev.size() * sizeof(Real));
    fnv1a(h, broken_flag.data(), broken_flag.size());
    fnv1a(h, grip_payout.data(), grip_payout.size() * sizeof(double));  // (none with rigid clamps)
    for (const auto& c : cr) fnv1a(h, &c.stick_w, sizeof(double));      // (the order of the arrays they were)
    for (const auto& c : cr) fnv1a(h, &c.stick_f, sizeof(double));
    fnv1a(h, xp.data(), sizeof(V3));
    fnv1a(h, vp.data(), sizeof(V3));
  }
};

}  // namespace ravel::detail

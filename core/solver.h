// The explicit solver: one time step as a short list of named stages.
//
// Why this order (paper §2-4, SPEC §3): Eq 1-2 integrate the free motion first, then the
// contact algorithms correct the *predicted* state, so that the state at the end of each
// step is free of interpenetration. step() runs exactly these, each a free function of
// (model, state, run state, context) declared in core/solver/stage.h and defined in its own
// file under core/solver/:
//
//   internal_forces       element strain -> Zener/elastic stress, bending springs, failure
//                         (internal_forces.cpp): the forces of Eq 1 from x(t); as it gathers
//                         each node's force it makes that node's free update, v += dt/m f
//                         (Eq 1), x += v dt (Eq 2) (stage.h: free_update): one sweep over
//                         the nodes and one barrier less than a separate pass
//   close_ledger_row      the ledger at t - dt/2 (ledger.cpp; needs this step's stored energy,
//                         see below; reads no node) and the energy-balance fault check
//                         (faults.cpp)
//   integrate             the rest of Eq 1-2: external loads on nodes, the projectile's free
//                         flight, the nodes' positions checked (integrate.cpp)
//   projectile_contact    normal push-out (Eq 18-19) and friction (Eq 20-22)
//                         (projectile_contact.cpp); before the yarn contact, so that the nodes
//                         it pushed out rest on the projectile while the yarns are corrected
//   yarn_contact          N passes of nearest-pair tracking, normal correction (Eq 5-11) with
//                         the compression law and stick/slip friction (Eq 12-15) on the
//                         predicted state (yarn_contact.cpp); last, so the yarn-yarn state is
//                         resolved at the end of every step
//   release_held          the yarn contact's push on nodes resting on the projectile, passed
//                         to the projectile (hold.cpp; the hold's whole rule is in hold.h)
//   residual_penetration  every 8th step, the interpenetration left (a diagnostic,
//                         yarn_contact.cpp)
//   finish_step           kinetic energy of the half-step velocities, the work of this step's
//                         corrections (ledger.cpp; with crossings the yarn contact's last pass
//                         takes these node sums as it applies its corrections, one sweep over
//                         the nodes less; without, only the projectile's nodes carry work)
//   check_projectile      every 16th step, a projectile gone non-finite or out of the domain
//                         (faults.cpp; the node and energy checks run inside integrate and
//                         close_ledger_row)
//
// Energy timing. Central differences carry velocities at half steps and positions at
// whole steps. The ledger is therefore evaluated at half steps: kinetic energy from
// v(t+dt/2) exactly, stored energy and the cumulative dashpot / release terms as the mean
// of their values at t and t+dt. With that pairing the ledger of an undamped linear
// network is conserved to O((omega dt)^2) without drift, which is what the energy tests
// rely on.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ledger.h"
#include "model.h"
#include "state_io.h"

namespace ravel {

// Counts of places where the method's assumptions broke (SPEC §4), with the first one.
struct ContactDiagnostics {
  long skipped_nodes = 0;  // yarns slid more than one node against each other in one step
  long repaired = 0;       // the nearest pair moved more than one node, the yarns less than half a node
  double first_repair_time = -1;
  int first_repair_i = 0, first_repair_j = 0;
  long ravelled = 0;        // a yarn slipped off the end of its partner: crossing released
  long passed_through = 0;  // yarns found passed through each other by more than D
  long lost_segments = 0;   // both adjoining segments broken: crossing released
  long separated = 0;       // side test flipped while the yarns were apart: released, not a fault
  long shift_broken = 0;    // elements stretched to failure by contact position shifts (modelled part)
  double first_shift_break_time = -1;
  double first_skip_time = -1, first_ravel_time = -1, first_pass_time = -1;
  int first_skip_i = 0, first_skip_j = 0, first_ravel_i = 0, first_ravel_j = 0, first_pass_i = 0, first_pass_j = 0;
  double max_penetration = 0;   // deepest yarn-yarn interpenetration left at the end of a step (m), sampled
  double last_penetration = 0;  // ... at the latest sample (every 8th step)
  bool balance_drift = false;   // the energy balance drifted past solver.max_balance_error slowly
  double balance_drift_time = -1;
};

// The precision-independent part of a run's dynamic state, as plain data (the solver's arrays
// are in core/solver/state.h): time, step count, the ledger, diagnostics, the fault that
// stopped the run, the last step's scalars and the projectile's contact history.
struct RunState {
  double time = 0;
  long steps = 0;
  Ledger ledger;  // at the latest half step (time - dt/2)
  ContactDiagnostics diag;
  std::string divergence, divergence_cause;  // empty: running
  long divergence_step = -1;
  double divergence_time = -1;
  int nodes_on_projectile = 0;
  double projectile_force = 0, yarn_force = 0, max_strain = 0;  // N, N, -
  int sliding_count = 0, stuck_count = 0;
  int broken[2] = {0, 0};  // elements broken so far, per family
  bool had_contact = false;
  double last_contact_time = -1;

  template <class Ar>
  void io(Ar& ar) {
    ar.mark(0x52564231);  // "RVB1"
    ar.pod(time);
    ar.pod(steps);
    ar.pod(ledger);
    ar.pod(diag);
    ar.str(divergence);
    ar.str(divergence_cause);
    ar.pod(divergence_step);
    ar.pod(divergence_time);
    ar.pod(nodes_on_projectile);
    ar.pod(projectile_force);
    ar.pod(yarn_force);
    ar.pod(max_strain);
    ar.pod(sliding_count);
    ar.pod(stuck_count);
    ar.pod(broken);
    ar.pod(had_contact);
    ar.pod(last_contact_time);
  }
};

// Precision-independent view of a solver (the Simulation holds one of two instantiations).
class Solver {
 public:
  virtual ~Solver() = default;
  const Model& model() const { return model_; }

  virtual void step() = 0;
  virtual void set_threads(int n) = 0;
  // Closest points of four crossings at once in AVX2 lanes where the processor has them
  // (on by default; bit-identical to one at a time, see solver/simd/contact_lanes.h). simd_active():
  // whether the lanes are used (on, double precision, an AVX2 processor).
  virtual void set_simd(bool on) = 0;
  virtual bool simd_active() const = 0;

  double time() const { return run_.time; }
  long steps() const { return run_.steps; }
  // Ledger of the modelled part at the latest half step (time() - dt/2).
  const Ledger& ledger() const { return run_.ledger; }
  double ledger_time() const { return run_.time - 0.5 * model_.dt; }
  const ContactDiagnostics& diagnostics() const { return run_.diag; }
  bool diverged() const { return !run_.divergence.empty(); }
  const std::string& divergence() const { return run_.divergence; }
  // The fault that stopped the run: cause ("non_finite", "energy_balance", "node_escaped"),
  // the step it happened in (steps completed before it) and the time then.
  const std::string& divergence_cause() const { return run_.divergence_cause; }
  long divergence_step() const { return run_.divergence_step; }
  double divergence_time() const { return run_.divergence_time; }

  // Projectile state (modelled part; mass is projectile_mass).
  virtual Vec3d projectile_position() const = 0;
  virtual Vec3d projectile_velocity() const = 0;
  // Node state in double.
  virtual Vec3d position(int node) const = 0;
  virtual Vec3d velocity(int node) const = 0;
  virtual void set_velocity(int node, const Vec3d& v) = 0;
  virtual void set_position(int node, const Vec3d& x) = 0;
  virtual void set_projectile_velocity(const Vec3d& v) = 0;
  virtual void set_projectile_position(const Vec3d& x) = 0;
  // A constant external force on a node (N), e.g. to press or pull yarns in tests; its
  // work is booked in the ledger as external_work_J.
  virtual void set_external_force(int node, const Vec3d& f) = 0;
  // Element state.
  virtual double strain(int e) const = 0;
  // Yarn a slipping clamp (Model::grips[g]) has fed into its element so far, m.
  virtual double grip_payout(int g) const = 0;
  virtual double stress(int e) const = 0;
  virtual bool broken(int e) const = 0;
  // Crossing state.
  virtual bool crossing_active(int c) const = 0;
  virtual bool crossing_sliding(int c) const = 0;
  virtual double crossing_normal_force(int c) const = 0;    // N (Eq 11), last step
  virtual double crossing_friction_force(int c) const = 0;  // N, magnitude of the resultant, last step
  virtual double crossing_slip_rate(int c) const = 0;       // m/s
  // The friction's Coulomb dissipation at crossing c so far: the sum over steps of its
  // friction force times its slip speed times dt (J, this modelled crossing; 0 at mu = 0
  // and while it sticks). Where friction heats the yarns; its sum over the crossings runs
  // somewhat above the ledger's friction_work_J (docs/MODEL.md §8).
  virtual double crossing_friction_heat(int c) const = 0;
  virtual double crossing_gap(int c) const = 0;     // |d| - D after the step (m), <0: penetration
  virtual int crossing_warp_node(int c) const = 0;  // tracked nearest node along the warp yarn
  virtual int crossing_weft_node(int c) const = 0;

  // Per step scalars.
  int nodes_on_projectile() const { return run_.nodes_on_projectile; }
  double projectile_contact_force() const { return run_.projectile_force; }  // N, modelled part
  double yarn_contact_force() const { return run_.yarn_force; }              // N, modelled part
  double max_strain() const { return run_.max_strain; }
  int sliding_crossings() const { return run_.sliding_count; }
  int stuck_crossings() const { return run_.stuck_count; }
  int broken_count(int family) const { return run_.broken[family]; }
  std::uint64_t state_hash() const;
  // The dynamic state, for checkpoints (core/state_io.h): everything a step carries to the
  // next. load_state reads it into a solver built from the same model (the caller checks).
  virtual void save_state(StateWriter& w) const = 0;
  virtual void load_state(StateReader& r) = 0;

  // Projectile contact history, for perforation detection.
  bool had_contact() const { return run_.had_contact; }
  double last_contact_time() const { return run_.last_contact_time; }
  // Stop the run: the method broke (cause: a short tag, why: the sentence after "diverged at
  // step N (t = T us): "). The solver's own checks call it (core/solver/faults.cpp), and so does
  // Simulation for the faults it judges against the scene. Only the first fault is kept.
  void fault(const std::string& cause, const std::string& why);
  // |ledger total - initial| / initial above this -> diverged.
  void set_max_balance_error(double f) { max_balance_error_ = f; }

 protected:
  explicit Solver(Model m) : model_(std::move(m)) {}
  virtual void hash_into(std::uint64_t& h) const = 0;
  Model model_;
  RunState run_;
  double max_balance_error_ = 0.05;
};

// Make the solver for a model in the scene's precision.
std::unique_ptr<Solver> make_solver(const Model& model, Precision precision, int threads);

}  // namespace ravel

// Simulation: the public face of the core. Builds the model a scene needs (quarter /
// half / full, sliding / pin-jointed), steps it, records the time history and the
// energy ledger, detects perforation, rebound and divergence, and hands out Frames.
//
// It owns no thread: callers (the CLI, the app's worker, tests, benchmarks) call step()
// or run() from whatever thread they like, one thread at a time.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "frame.h"
#include "ledger.h"
#include "scene.h"

namespace ravel {

enum class RunStatus { running, completed, diverged, interrupted };
enum class EndReason { none, perforated, rebounded, caught, end_time, diverged, interrupted };

const char* to_string(RunStatus s);
const char* to_string(EndReason r);

// One row of history.csv. Energies are for the whole fabric (a quarter model's are x4).
struct HistoryRow {
  double t_s = 0;
  double projectile_z_m = 0, projectile_velocity_mps = 0;  // velocity along the flight path (+ = into the fabric)
  Ledger ledger;                                           // energies in J
  double balance_error = 0;                                // (sum of ledger - initial) / initial
  int broken_warp = 0, broken_weft = 0;                    // broken elements per family (whole fabric)
  double max_strain = 0;
  double projectile_contact_force_N = 0;  // magnitude, whole projectile
  double yarn_contact_force_N = 0;        // sum of yarn-yarn normal forces (whole fabric)
  int nodes_on_projectile = 0;
  int sliding_crossings = 0, stuck_crossings = 0;  // whole fabric; 0 for pin-jointed
};

struct Summary {
  std::string scene_name;
  RunStatus status = RunStatus::running;
  EndReason end_reason = EndReason::none;
  std::string diagnosis;  // why it diverged / was interrupted, in words
  // A diverged run: what stopped it (non_finite, energy_balance, node_escaped,
  // projectile_left_domain, search_lost), the step it happened in and the simulated time.
  std::string divergence_cause;
  long divergence_step = -1;
  double divergence_time_s = -1;
  bool perforated = false;
  double impact_velocity_mps = 0;
  double residual_velocity_mps = 0;  // speed along the flight path at the end (perforation: exit speed)
  double energy_absorbed_J = 0;      // M (V0^2 - Vr^2) / 2
  double perforation_time_s = -1;    // < 0: none
  // Perforated by solver.decide_passing's early decision (the run stopped while the projectile
  // was still dragging yarns: residual velocity and perforation time are those of the decision).
  bool decided_passing = false;
  double energy_balance_error = 0;  // worst |balance error| over the run
  double friction_work_J = 0;       // yarn-yarn friction work over the whole run
  double clamp_friction_J = 0;      // slipping clamps' dissipation over the whole run (0: rigid clamps)
  double clamp_slip_max_m = 0;      // slipping clamps: the most yarn one clamp fed out (it only grows)
  double clamp_pulled_out = 0;      // ... and the yarns pulled out of their clamps (whole fabric)
  // ... up to the first broken element (the whole run if none broke) and up to perforation
  // (the whole run if it did not perforate): the windows of docs/MODEL.md §8.
  double friction_work_to_first_break_J = 0;
  double friction_work_to_perforation_J = 0;
  double first_break_time_s = -1;      // < 0: no element broke
  double first_break_distance_m = -1;  // in-plane distance of the first break from the aim point
  // Elements broken before perforation (every break, if it did not perforate), whole fabric,
  // and those of them whose midpoint lies within 2 mm of a clamped edge.
  int broken_before_perforation = 0, broken_near_clamp = 0;
  std::string model;          // quarter | half | full
  std::string model_reason;   // why that model
  std::string contact_model;  // sliding | pin_jointed
  // The whole fabric (what every count, energy and history column describes) ...
  int node_count = 0, element_count = 0, crossing_count = 0;
  // ... and the part the solver models (quarter / half / full, see `model`).
  int modelled_node_count = 0, modelled_element_count = 0, modelled_crossing_count = 0;
  long step_count = 0;
  double dt_s = 0;
  double end_time_s = 0;
  double wall_time_s = 0;
  double node_steps_per_s = 0;
  int broken_warp = 0, broken_weft = 0;
  int broken_warp_yarns = 0, broken_weft_yarns = 0;  // yarns with at least one broken element
  // ... and their grid lines, ascending: the warp at x = I L0, the weft at y = J L0, counted
  // from the strike point's line (0) over the whole fabric; a modelled yarn off a symmetry
  // plane stands for its mirror images too (I and -I).
  std::vector<int> broken_warp_lines, broken_weft_lines;
  double max_strain = 0;
  std::vector<std::string> warnings;
};

class Solver;  // core/solver.h

class Simulation {
 public:
  explicit Simulation(const Scene& scene);
  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  // Advance one time step. Returns false when the run is over (see summary().status).
  bool step();
  // Run until done, or until `interrupt` becomes true. `on_sample` is called after each
  // history sample (progress display).
  void run(const std::atomic<bool>* interrupt = nullptr, const std::function<void(const Simulation&)>& on_sample = {});
  // A run that ended at its end time undecided (neither perforated nor stopped) goes on to
  // a later end time: run() continues it. Returns false (and changes nothing) for any other
  // state. Studies use it so that no undecided run counts as stopped (SPEC §8).
  bool extend_to(double end_time_s);
  // The end time the run goes to (the model's, or the latest extend_to).
  double end_time_s() const;
  // Mark the run interrupted (Ctrl-C) and finish the summary.
  void interrupt(const std::string& why);

  bool finished() const;
  double time_s() const;
  long step_count() const;
  double dt_s() const;
  const Scene& scene() const;
  const std::vector<HistoryRow>& history() const;
  Summary summary() const;
  Frame frame() const;
  // A hash of the full dynamic state (positions, velocities, internal variables), for
  // determinism checks.
  std::uint64_t state_hash() const;

  // Checkpoints (`ravel run --resume`): the run so far as bytes (core/state_io.h), and a
  // Simulation built from the same scene continued from such bytes, exactly as if it had
  // never stopped. restore() throws std::runtime_error, changing nothing, when the bytes
  // are not a checkpoint of this scene (solver threads aside) from this ravel build.
  std::string checkpoint() const;
  void restore(const std::string& bytes);
  // What a checkpoint must match: the scene as TOML (solver threads aside) and the build.
  std::string checkpoint_fingerprint() const;

  // Direct access for tests and studies.
  const Solver& solver() const;
  Solver& solver();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ravel

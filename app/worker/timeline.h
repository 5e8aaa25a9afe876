// Timeline: the frames of the run on screen, kept so the app can go back in time.
//
// The worker publishes a Frame every ~15 ms of stepping; the UI hands each new one to
// add(). A kept frame stores only what changes during a run (node positions, velocities
// and slip rates, element strains, stresses and broken flags, the crossings' forces and
// slip, the projectile, the time); what does not (element connectivity, yarn ids, the
// fabric's outline) is stored once, from the first frame of the run, and frame(i)
// rebuilds a whole Frame from both.
//
// Memory budget. A kept frame of the default scene's quarter model costs about 0.47 MB
// (10,368 nodes, 10,224 elements, 5,112 crossings). The timeline keeps frames at least
// `spacing` of simulated time apart (0 at first: every published frame); when the kept
// frames would exceed the budget it doubles the spacing and drops the frames that no
// longer keep it (never the first or the newest), so a run of any length fits and its
// frames stay evenly spread over it. The default budget, 256 MB, holds about 540 frames of
// the default scene: a 300 us run every 0.56 us or better.
//
// Plain data and no GL: unit-tested on its own (tests/app/timeline_test.cpp).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "frame.h"

namespace ravel::app {

class Timeline {
 public:
  explicit Timeline(std::size_t budget_bytes = std::size_t(256) << 20) : budget_(budget_bytes) {}

  // Forget everything (a new run); `run_id` tags the frames that follow.
  void reset(long run_id);
  long run_id() const { return run_id_; }
  // Keep `f` if it is later than the newest kept frame by at least the spacing (the
  // newest is always replaced by a later frame that comes too soon, so the timeline ends
  // where the run is). `step` is the run's step count when the frame was taken.
  void add(const Frame& f, long step);

  std::size_t size() const { return kept_.size(); }
  bool empty() const { return kept_.empty(); }
  double time(std::size_t i) const { return kept_[i].time_s; }
  long step(std::size_t i) const { return kept_[i].step; }
  double first_time() const { return kept_.empty() ? 0.0 : kept_.front().time_s; }
  double last_time() const { return kept_.empty() ? 0.0 : kept_.back().time_s; }
  // The last kept frame at or before t (the first one if t is earlier than all).
  std::size_t index_at(double t_s) const;
  // Frame i rebuilt whole.
  Frame frame(std::size_t i) const;
  // One element's strain / stress at kept frame i (for the picked item's history chart,
  // without rebuilding frames).
  // (0 / false for an index the frame does not have.)
  float strain(std::size_t i, std::size_t element) const { return at(kept_[i].elem_strain, element); }
  float stress(std::size_t i, std::size_t element) const { return at(kept_[i].elem_stress_pa, element); }
  bool broken(std::size_t i, std::size_t element) const { return at(kept_[i].elem_broken, element) != 0; }
  float crossing_force(std::size_t i, std::size_t c) const { return at(kept_[i].crossing_normal_force_n, c); }
  float crossing_slip(std::size_t i, std::size_t c) const { return at(kept_[i].crossing_slip_rate, c); }

  std::size_t bytes() const { return bytes_; }  // what the kept frames hold now
  std::size_t budget_bytes() const { return budget_; }
  void set_budget_bytes(std::size_t b);
  double spacing_s() const { return spacing_; }
  long frames_seen() const { return seen_; }

 private:
  struct Kept {
    double time_s = 0;
    long step = 0;
    bool perforated = false;
    std::array<float, 3> projectile_pos{0, 0, 0};
    std::vector<std::array<float, 3>> node_pos, node_vel;
    std::vector<float> node_slip_rate, node_friction_j_per_g, elem_strain, elem_stress_pa;
    std::vector<std::uint8_t> elem_broken;
    std::vector<std::uint32_t> crossing_warp_node, crossing_weft_node;
    std::vector<float> crossing_normal_force_n, crossing_slip_rate;
    std::vector<std::uint8_t> crossing_active;
    std::size_t bytes() const;
  };
  static Kept keep(const Frame& f, long step);
  template <class T>
  static T at(const std::vector<T>& v, std::size_t i) {
    return i < v.size() ? v[i] : T{};
  }
  void thin();

  std::size_t budget_;
  std::size_t bytes_ = 0;
  long run_id_ = -1;
  double spacing_ = 0;
  long seen_ = 0;
  Frame skeleton_;  // the run's first frame without its per-frame arrays
  std::vector<Kept> kept_;
};

}  // namespace ravel::app

// Guided demos for lectures and labs (issue 9): the catalogue, the wave theory their
// overlays draw, and a GL-free runner that steps a demo's runs in step with each other.
//
// A demo is a few runs (a scene + overrides each) shown side by side with one clock, key
// frames (simulated times) where it pauses with a two-line caption, and the charts it
// hands out. The app's Demos menu (app/gui_compare.cpp) and `ravel demo NAME --out DIR`
// (app/cli/cmd_demo.cpp, headless PNGs through app/demos/demo_render.*) both read this catalogue;
// docs/demos.md explains each demo to teachers.
#pragma once

#include <functional>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "simulation.h"

namespace ravel::app::demos {

// ---- Theory ----------------------------------------------------------------------------

// Longitudinal wave speed of the yarn: sqrt(E / rho), with E = K1 (the Zener model's
// instantaneous modulus) or the elastic modulus.
double longitudinal_speed(const Scene& scene);

// Smith's classical theory of a single yarn struck transversely at speed V (yarn wave
// speed c): the strain eps behind the fronts solves V = c sqrt(2 eps sqrt(eps (1 + eps)) - eps^2),
// and the transverse front runs at U = c (sqrt(eps (1 + eps)) - eps) (Lagrangian).
struct SmithWave {
  double strain = 0;
  double transverse_speed_mps = 0;    // U, Lagrangian
  double longitudinal_speed_mps = 0;  // c
};
SmithWave smith_wave(double impact_velocity_mps, double c_mps);

// ---- Catalogue -------------------------------------------------------------------------

struct DemoRun {
  std::string label;                   // "mu = 0.02" (viewport title, chart legend)
  std::vector<std::string> overrides;  // on top of the demo's scene (`key=value`)
};

// What a key frame shows. `t_us` < 0: the end of the runs (all finished, or the end time).
struct KeyFrame {
  double t_us = 0;
  std::string line1, line2;  // the two-line caption; {counts} style fields are filled in, see caption()
};

enum class Overlay { none, wave_fronts };
enum class DemoChart { velocity_history, broken_yarns };

struct Demo {
  std::string name;                    // command-line name: waves, friction, slit, limit, heat
  std::string title;                   // menu entry
  std::string summary;                 // one sentence for --list and the menu tooltip
  std::string scene = "twaron_ct716";  // shipped scene name or TOML path
  std::vector<std::string> overrides;  // for every run
  std::vector<DemoRun> runs;           // 1 to 4
  std::vector<KeyFrame> key_frames;    // in time order
  double end_time_us = 300;            // the runs stop here at the latest
  std::string view = "oblique";        // camera preset for the viewports
  std::string field = "strain";        // colour field
  float range_max = 0;                 // colour range upper end (0 = the field's default)
  Overlay overlay = Overlay::none;
  std::vector<DemoChart> charts;
  double slow_motion_us_per_s = 10;  // app pacing (simulated us per wall second)
  std::string note;                  // what the demo's settings change vs the paper (caption / docs)
};

// The catalogue. `quick`: cheaper settings for tests (smaller fabric, fewer and earlier
// key frames); the point each demo makes is kept where it can be.
const std::vector<Demo>& catalogue(bool quick = false);
const Demo* find_demo(const std::string& name, bool quick = false);

// The pre-measured ballistic limit that demo "limit" straddles, and how it was measured.
struct MeasuredLimit {
  double limit_mps, lo_mps, hi_mps;
  const char* how;
};
MeasuredLimit limit_demo_measurement();

// Scene for run i of a demo (the demo's scene, its overrides, then the run's). Throws SceneError.
Scene demo_scene(const Demo& demo, std::size_t run);

// ---- State at a key frame and captions --------------------------------------------------

struct RunState {
  std::string label;
  Frame frame;
  Summary summary;
  std::vector<HistoryRow> history;  // from t = 0 to the frame
};

// The caption's two lines with the fields filled in from the runs: {wL} {wT} (theory
// front radii in mm), {c} {U} (speeds), {eps} (Smith strain in %), {broken} (broken
// yarns per direction for every run), {vr} (projectile speed of every run), {bl} (the
// measured limit), {t} (time in us), {mL} {mT} (fronts measured on run 0's frame, mm).
std::vector<std::string> caption(const Demo& demo, const KeyFrame& key, const std::vector<RunState>& runs);

// The wave fronts a frame should show (radii in m from the strike point): longitudinal
// c t and transverse U t, t from the moment of impact (the projectile starts touching
// the fabric: ravel places it there, core/model.cpp).
struct WaveFronts {
  double longitudinal_m = 0, transverse_m = 0;
  SmithWave wave;
};
WaveFronts wave_fronts(const Scene& scene, double t_s);

// The fronts measured on a frame, along the two yarns through the strike point (x and y
// axes): the farthest node whose speed exceeds a quarter of the theoretical in-flow
// speed c eps (longitudinal) and whose out-of-plane speed exceeds 30 % of V0
// (transverse). -1 where none is found.
struct MeasuredFronts {
  double longitudinal_m = -1, transverse_m = -1;
};
MeasuredFronts measure_fronts(const Scene& scene, const Frame& frame);

// ---- Shared clock (the app's split viewports) ---------------------------------------------

// The clock that keeps 2-4 runs in step (app/gui/gui_demos.h): it advances at the slow-motion
// rate, never more than `lead_s` ahead of the slowest run, and never past the next stop
// (a key frame). Each run is paused when it reaches the clock, so the slowest gates all.
class SharedClock {
 public:
  // Simulated seconds per wall second; <= 0: as fast as the slowest run allows.
  void set_rate(double rate_s_per_s) { rate_ = rate_s_per_s; }
  double rate() const { return rate_; }
  // Advance by wall time dt_s. run_times_s: each run's time (a finished run: +inf);
  // stop_s < 0: no stop. Returns the new time; the clock never goes back.
  double advance(double dt_s, const std::vector<double>& run_times_s, double stop_s, double lead_s);
  double time() const { return t_; }
  void reset() { t_ = 0; }

 private:
  double t_ = 0, rate_ = 10e-6;
};

// ---- Runner ----------------------------------------------------------------------------

// Steps every run of a demo to the same simulated time, each on its own thread (a
// Simulation owns no thread and is used by one thread at a time). Runs that end early
// (perforation, rebound) stay at their last state.
class DemoRunner {
 public:
  // `interrupt` (optional): when it becomes true the runs stop between steps and
  // advance_to / run_to_end throw std::runtime_error("interrupted").
  DemoRunner(const Demo& demo, int solver_threads = 1, const std::atomic<bool>* interrupt = nullptr);
  ~DemoRunner();
  // Advance every run to time t_s (each to its step closest to t_s) or its end.
  void advance_to(double t_s);
  // Advance every run to its end (finished, or the demo's end time).
  void run_to_end();
  bool all_finished() const;
  double time_s() const;  // the slowest run's time
  std::vector<RunState> state() const;
  const Demo& demo() const { return demo_; }
  const Simulation& simulation(std::size_t i) const { return *sims_[i]; }
  std::size_t size() const { return sims_.size(); }

 private:
  Demo demo_;
  std::vector<std::unique_ptr<Simulation>> sims_;
  const std::atomic<bool>* interrupt_ = nullptr;
};

}  // namespace ravel::app::demos

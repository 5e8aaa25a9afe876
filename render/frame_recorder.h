// FrameRecorder: images (PNG, offscreen) and a ParaView series (VTU + PVD) written while a
// run advances, for `ravel run --frames every=N|final|none [--vtk]`.
//
// Schedule: `every=N` writes the initial state, then a frame each time another N time
// steps have passed (taken at the next history sample, where the run loop calls
// on_sample), and the final state; `final` only the final state; `none` nothing. `--vtk`
// writes a VTU at the same instants (every=100 when no frames are asked for).
// PNGs go to DIR/frames/frame_NNNNN.png, the series to DIR/vtk/frame.pvd.
#pragma once

#include <memory>
#include <string>

#include "core/simulation.h"
#include "core/vtk.h"
#include "render/renderer.h"

namespace ravel::render {

struct RecorderOptions {
  enum class Mode { none, every, final_only };
  Mode mode = Mode::none;
  long every_steps = 100;
  bool png = false;  // write PNGs (false: only the VTU series)
  bool vtk = false;
  ViewOptions view;
  int width = 1280, height = 960;
  std::string dir;  // the run's output folder
};

// Parse "every=N", "final" or "none" into options->mode / every_steps.
bool parse_frames_spec(const std::string& spec, RecorderOptions* options, std::string* error);

class FrameRecorder {
 public:
  // nullptr (with a reason) when the folders or the offscreen context cannot be made.
  static std::unique_ptr<FrameRecorder> create(const RecorderOptions& options, std::string* error);
  ~FrameRecorder();
  bool active() const;
  // Call after each history sample (Simulation::run's on_sample); writes when due.
  bool on_sample(const Simulation& sim, std::string* error);
  // Call once the run is over: writes the final state.
  bool finish(const Simulation& sim, std::string* error);
  int images_written() const { return images_; }
  int vtk_written() const { return series_ ? series_->count() : 0; }

 private:
  FrameRecorder() = default;
  bool write(const Simulation& sim, std::string* error);
  RecorderOptions options_;
  std::unique_ptr<HeadlessRenderer> renderer_;
  std::unique_ptr<VtkSeries> series_;
  long next_step_ = 0;
  long last_written_step_ = -1;
  int images_ = 0;
};

}  // namespace ravel::render

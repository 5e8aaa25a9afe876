#include "render/frame_recorder.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>

namespace ravel::render {

bool parse_frames_spec(const std::string& spec, RecorderOptions* o, std::string* error) {
  if (spec == "none") {
    o->mode = RecorderOptions::Mode::none;
    return true;
  }
  if (spec == "final") {
    o->mode = RecorderOptions::Mode::final_only;
    return true;
  }
  if (spec.rfind("every=", 0) == 0) {
    char* end = nullptr;
    const long n = std::strtol(spec.c_str() + 6, &end, 10);
    if (spec.size() > 6 && *end == '\0' && n >= 1 && n <= 100000000) {
      o->mode = RecorderOptions::Mode::every;
      o->every_steps = n;
      return true;
    }
  }
  if (error) *error = "--frames: expected every=N (N time steps >= 1), final or none, got '" + spec + "'";
  return false;
}

std::unique_ptr<FrameRecorder> FrameRecorder::create(const RecorderOptions& options, std::string* error) {
  std::unique_ptr<FrameRecorder> r(new FrameRecorder());
  r->options_ = options;
  if (options.vtk && options.mode == RecorderOptions::Mode::none) {
    r->options_.mode = RecorderOptions::Mode::every;  // a series needs instants
    r->options_.every_steps = 100;
  }
  if (!r->active()) return r;
  std::error_code ec;
  if (options.png) {
    std::filesystem::create_directories(options.dir + "/frames", ec);
    if (ec) {
      if (error) *error = options.dir + "/frames: " + ec.message();
      return nullptr;
    }
    r->renderer_ = HeadlessRenderer::create(error);
    if (!r->renderer_) return nullptr;
  }
  if (options.vtk) {
    std::filesystem::create_directories(options.dir + "/vtk", ec);
    if (ec) {
      if (error) *error = options.dir + "/vtk: " + ec.message();
      return nullptr;
    }
    r->series_ = std::make_unique<VtkSeries>(options.dir + "/vtk", "frame");
  }
  return r;
}

FrameRecorder::~FrameRecorder() = default;

bool FrameRecorder::active() const {
  return options_.mode != RecorderOptions::Mode::none && (options_.png || options_.vtk);
}

bool FrameRecorder::write(const Simulation& sim, std::string* error) {
  if (sim.step_count() == last_written_step_) return true;
  last_written_step_ = sim.step_count();
  const Frame frame = sim.frame();
  if (renderer_) {
    char name[64];
    std::snprintf(name, sizeof name, "/frames/frame_%05d.png", images_);
    if (!renderer_->render_png(frame, options_.view, options_.width, options_.height, options_.dir + name, error))
      return false;
    ++images_;
  }
  return !series_ || series_->add(frame, error);
}

bool FrameRecorder::on_sample(const Simulation& sim, std::string* error) {
  if (!active() || options_.mode != RecorderOptions::Mode::every) return true;
  if (sim.step_count() < next_step_) return true;
  while (next_step_ <= sim.step_count()) next_step_ += options_.every_steps;
  return write(sim, error);
}

bool FrameRecorder::finish(const Simulation& sim, std::string* error) {
  return !active() || write(sim, error);
}

}  // namespace ravel::render

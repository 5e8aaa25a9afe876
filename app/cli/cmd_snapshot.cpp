// `ravel snapshot [SCENE] [--set k=v ...] --at TIME_US[,TIME_US...] [--view NAME]
//  [--size WxH] [--field NAME] [--range LO:HI] --out DIR`
//
// Runs the scene and, as simulated time passes each requested instant, draws the fabric
// offscreen (OSMesa, no display needed) and writes DIR/<scene>_<view>_t<TIME>us.png.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "cli.h"
#include "commands.h"
#include "render/renderer.h"
#include "results.h"
#include "simulation.h"

namespace ravel::app {

namespace {

std::vector<double> parse_times_us(const std::string& text) {
  std::vector<double> times;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double t = std::strtod(item.c_str(), &end);
    if (item.empty() || *end || !std::isfinite(t) || t < 0)
      throw UsageError("--at: expected times in microseconds >= 0 separated by commas, got '" + item + "'");
    times.push_back(t);
  }
  if (times.empty()) throw UsageError("--at needs at least one time in microseconds");
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

void parse_size(const std::string& text, int* w, int* h) {
  char x = 0;
  char rest = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", w, &x, h, &rest) != 3 || (x != 'x' && x != 'X') || *w < 16 || *h < 16 ||
      *w > 8192 || *h > 8192)
    throw UsageError("--size: expected WxH between 16x16 and 8192x8192, got '" + text + "'");
}

}  // namespace

int cmd_snapshot(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "snapshot");
    if (a.out_dir.empty()) throw UsageError("snapshot needs --out DIR");
    if (!a.flags.count("at")) throw UsageError("snapshot needs --at TIME_US[,TIME_US...]");
    const std::vector<double> times_us = parse_times_us(a.flags["at"]);

    render::ViewOptions view;
    if (a.flags.count("view") && !render::parse_view_preset(a.flags["view"], &view.view))
      throw UsageError("--view: expected " + render::view_preset_names() + ", got '" + a.flags["view"] + "'");
    if (a.flags.count("field") && !render::parse_color_field(a.flags["field"], &view.field))
      throw UsageError("--field: expected " + render::color_field_names() + ", got '" + a.flags["field"] + "'");
    if (a.flags.count("range")) {
      char colon = 0;
      if (std::sscanf(a.flags["range"].c_str(), "%f%c%f", &view.range_min, &colon, &view.range_max) != 3 ||
          colon != ':' || !(view.range_max > view.range_min))
        throw UsageError("--range: expected LO:HI with LO < HI, got '" + a.flags["range"] + "'");
    }
    int width = 1600, height = 1200;
    if (a.flags.count("size")) parse_size(a.flags["size"], &width, &height);
    const bool quiet = has_switch(a, "quiet");

    Scene scene = load_scene_from(a);
    // Run long enough to reach the last requested time.
    scene.solver.end_time_s = std::max(scene.solver.end_time_s, times_us.back() * 1e-6);
    prepare_output_dir(a.out_dir);

    std::string error;
    auto renderer = render::HeadlessRenderer::create(&error);
    if (!renderer) throw OutputError("cannot create an offscreen OpenGL context: " + error);

    Simulation sim(scene);
    int written = 0;
    for (const double t_us : times_us) {
      const double target_s = t_us * 1e-6;
      // Stop at the step closest to the requested time.
      while (!sim.finished() && sim.time_s() + 0.5 * sim.dt_s() < target_s) sim.step();
      const Frame frame = sim.frame();
      if (sim.time_s() + 0.5 * sim.dt_s() < target_s)
        std::fprintf(stderr,
                     "ravel: warning: the run ended at %.2f us (%s); the image for %.2f us shows "
                     "that final state\n",
                     sim.time_s() * 1e6, to_string(sim.summary().end_reason), t_us);
      // <scene>[+<tag of the --set overrides>]_<view>[_<field>]_t<T>us.png: the name never
      // leaves --out, and images of other overrides or fields do not overwrite these.
      std::string stem = safe_file_name(scene.name);
      if (!a.overrides.empty()) {
        std::string all;
        for (const auto& o : a.overrides) all += o + "\n";
        stem += "+" + short_hash(all);
      }
      stem += std::string("_") + render::to_string(view.view);
      if (view.field != render::ViewOptions{}.field) stem += std::string("_") + render::to_string(view.field);
      char time_tag[64];
      std::snprintf(time_tag, sizeof time_tag, "_t%07.2fus.png", t_us);
      const std::string path = a.out_dir + "/" + stem + time_tag;
      if (!renderer->render_png(frame, view, width, height, path, &error)) throw OutputError(path + ": " + error);
      ++written;
      if (!quiet) std::printf("%s  (t = %.2f us)\n", path.c_str(), frame.time_s * 1e6);
    }
    if (sim.summary().status == RunStatus::diverged) {
      std::fprintf(stderr, "ravel: the run diverged: %s\n", sim.summary().diagnosis.c_str());
      return exit_diverged;
    }
    return written > 0 ? exit_ok : exit_failure;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

}  // namespace ravel::app

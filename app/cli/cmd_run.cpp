// `ravel run [SCENE] [--set k=v ...] --out DIR`: one headless run, written as
// DIR/history.csv, DIR/summary.json and DIR/scene.toml.
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "cli.h"
#include "commands.h"
#include "results.h"
#include "model.h"
#include "simulation.h"
#include "solver.h"
#include "sweep.h"     // studies/: read_text_file
#include "tradeoff.h"  // studies/: suggestions from measured speed/accuracy trade-offs
#ifdef RAVEL_HAVE_SNAPSHOT
#include "render/frame_recorder.h"  // --frames / --vtk (render/ owner)
#endif

namespace ravel::app {

namespace {
std::atomic<bool> g_interrupt{false};
extern "C" void on_signal(int) {
  g_interrupt.store(true);
}
}  // namespace

std::atomic<bool>& interrupt_flag() {
  return g_interrupt;
}

void install_signal_handlers() {
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
}

// Test hook (docs/robustness.md): RAVEL_TEST_FAULT=nan@STEP or search_lost@STEP breaks the
// state after that many steps, so the CLI tests can drive each fault class to its exit
// code. Faults a scene can cause (energy runaway, projectile leaving the domain) are tested
// with scenes instead.
void inject_test_fault(Simulation& sim) {
  const char* spec = std::getenv("RAVEL_TEST_FAULT");
  if (!spec || !*spec) return;
  const std::string s = spec;
  const auto at = s.find('@');
  const std::string what = s.substr(0, at);
  const long step = at == std::string::npos ? 0 : std::atol(s.c_str() + at + 1);
  while (sim.step_count() < step && sim.step()) {
  }
  if (sim.finished()) return;
  Solver& solver = sim.solver();
  const Model& m = solver.model();
  if (what == "nan") {
    solver.set_position(m.yarn_node(0, m.yarn_size(0) / 2), Vec3d::Constant(std::nan("")));
  } else if (what == "search_lost") {
    // Every weft yarn jumps 2.5 node spacings along itself: a rigid shift (no strain, no
    // kinetic energy), so only the nearest-pair search notices.
    for (int y = 0; y < m.yarn_count(); ++y) {
      if (m.yarn_family[y] != weft) continue;
      for (int k = 0; k < m.yarn_size(y); ++k) {
        const int i = m.yarn_node(y, k);
        solver.set_position(i, solver.position(i) + Vec3d(2.5 * sim.scene().fabric.spacing_m, 0, 0));
      }
    }
  } else {
    std::fprintf(stderr, "ravel: RAVEL_TEST_FAULT=%s: unknown fault (nan@STEP, search_lost@STEP)\n", spec);
    std::exit(exit_usage);
  }
}

// A run owns its output folder's run files: the ones an earlier run into the same --out
// wrote (frames/frame_*.png, vtk/frame_*.vtu and frame.pvd, history.csv, summary.json,
// scene.toml) go before this one starts, so ParaView's series and the frames never mix two
// runs. Other files are left alone.
void clear_earlier_run(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  int removed = 0;
  auto remove_matching = [&](const fs::path& sub, const std::string& prefix, const std::string& ext) {
    if (!fs::is_directory(sub, ec)) return;
    for (const auto& entry : fs::directory_iterator(sub, ec)) {
      const std::string n = entry.path().filename().string();
      if (entry.is_regular_file(ec) && n.rfind(prefix, 0) == 0 && entry.path().extension() == ext &&
          fs::remove(entry.path(), ec))
        ++removed;
    }
  };
  remove_matching(fs::path(dir) / "frames", "frame_", ".png");
  remove_matching(fs::path(dir) / "vtk", "frame_", ".vtu");
  remove_matching(fs::path(dir) / "vtk", "frame", ".pvd");
  for (const char* f : {"history.csv", "summary.json", "scene.toml"})
    if (fs::remove(fs::path(dir) / f, ec)) ++removed;
  if (removed > 0)
    std::fprintf(stderr, "ravel: %s held an earlier run: its %d run files were removed first\n", dir.c_str(), removed);
}

void print_summary_line(const Summary& s, const std::string& out_dir) {
  std::printf("%s: %s (%s), model %s %s, %d of the fabric's %d nodes, %ld steps in %.2f s\n", s.scene_name.c_str(),
              to_string(s.status), to_string(s.end_reason), s.model.c_str(), s.contact_model.c_str(),
              s.modelled_node_count, s.node_count, s.step_count, s.wall_time_s);
  if (s.perforated)
    std::printf("  perforated at %.1f us, residual velocity %.1f m/s, energy absorbed %.2f J\n",
                s.perforation_time_s * 1e6, s.residual_velocity_mps, s.energy_absorbed_J);
  else
    std::printf("  not perforated, energy absorbed %.2f J\n", s.energy_absorbed_J);
  std::string lines;  // where they lie: grid lines from the aim point's (0)
  if (!s.broken_warp_lines.empty()) lines += "warp lines " + line_ranges(s.broken_warp_lines);
  if (!s.broken_weft_lines.empty())
    lines += (lines.empty() ? "" : ", ") + ("weft lines " + line_ranges(s.broken_weft_lines));
  std::printf("  broken yarns: %d warp, %d weft%s; energy balance error %.2e\n", s.broken_warp_yarns,
              s.broken_weft_yarns, lines.empty() ? "" : (" (" + lines + ")").c_str(), s.energy_balance_error);
  if (s.status == RunStatus::diverged || s.status == RunStatus::interrupted) std::printf("  %s\n", s.diagnosis.c_str());
  for (const auto& w : s.warnings) std::printf("  warning: %s\n", w.c_str());
  if (!out_dir.empty()) {
    // Every output this run wrote (the folder was cleared of an earlier run's first).
    namespace fs = std::filesystem;
    std::error_code ec;
    std::string what = "summary.json, history.csv, scene.toml";
    int pngs = 0;
    if (fs::is_directory(out_dir + "/frames", ec))
      for (const auto& e : fs::directory_iterator(out_dir + "/frames", ec))
        pngs += e.path().filename().string().rfind("frame_", 0) == 0 && e.path().extension() == ".png";
    if (pngs) what += ", frames/ (" + std::to_string(pngs) + " PNG)";
    if (fs::exists(out_dir + "/vtk/frame.pvd", ec)) what += ", vtk/frame.pvd";
    std::printf("  results in %s/ (%s)\n", out_dir.c_str(), what.c_str());
  }
}

int cmd_run(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "run");
    if (a.out_dir.empty()) throw UsageError("run needs --out DIR");
    // Checked before anything that depends on the build, so every build says the same.
    const bool resume = has_switch(a, "resume");
    if (resume && (a.flags.count("frames") || has_switch(a, "vtk")))
      throw UsageError(
          "--resume cannot be combined with --frames or --vtk (the frames before the checkpoint are gone)");
#ifdef RAVEL_HAVE_SNAPSHOT
    render::RecorderOptions rec;
    std::string rec_error;
    if (a.flags.count("frames") && !render::parse_frames_spec(a.flags["frames"], &rec, &rec_error))
      throw UsageError(rec_error);
    if (a.flags.count("view") && !render::parse_view_preset(a.flags["view"], &rec.view.view))
      throw UsageError("--view: expected " + render::view_preset_names());
    if (a.flags.count("field") && !render::parse_color_field(a.flags["field"], &rec.view.field))
      throw UsageError("--field: expected " + render::color_field_names());
    rec.png = rec.mode != render::RecorderOptions::Mode::none;
    rec.vtk = has_switch(a, "vtk");
    rec.dir = a.out_dir;
#else
    if (a.flags.count("frames") || has_switch(a, "vtk"))
      throw UsageError("--frames / --vtk need a build with the renderer (RAVEL_BUILD_GUI=ON)");
#endif
    // Checkpoints: DIR/checkpoint.bin every --checkpoint-every seconds and on Ctrl-C, gone
    // when the run ends; --resume continues from it (Simulation::restore checks that it is
    // this scene's, from this build).
    double checkpoint_every_s = 60;
    if (a.flags.count("checkpoint-every")) {
      char* end = nullptr;
      checkpoint_every_s = std::strtod(a.flags["checkpoint-every"].c_str(), &end);
      if (a.flags["checkpoint-every"].empty() || *end || !(checkpoint_every_s >= 0))
        throw UsageError("--checkpoint-every: expected seconds >= 0 (0 = never), got '" + a.flags["checkpoint-every"] +
                         "'");
    }
    const std::string checkpoint_path = a.out_dir + "/checkpoint.bin";
    Scene scene = load_scene_from(a);
    // Said before a run that may take hours, not only in the summary at its end.
    for (const auto& w : scene.warnings) std::fprintf(stderr, "ravel: warning: %s\n", w.c_str());
    prepare_output_dir(a.out_dir);
    Simulation sim(scene);
    std::string kept;
    if (resume) {
      std::error_code ec;
      if (std::filesystem::exists(checkpoint_path, ec)) {
        kept = studies::read_text_file(checkpoint_path);
        try {
          sim.restore(kept);
        } catch (const std::exception& e) {
          throw SceneError("", checkpoint_path,
                           std::string(e.what()) + " (it is kept; --out another folder or drop --resume)");
        }
        std::fprintf(stderr, "ravel: resuming from %s at t = %.2f us (step %ld)\n", checkpoint_path.c_str(),
                     sim.time_s() * 1e6, sim.step_count());
      } else {
        std::fprintf(stderr, "ravel: --resume: no checkpoint in %s; starting at t = 0\n", a.out_dir.c_str());
      }
    }
    if (kept.empty()) clear_earlier_run(a.out_dir);
    install_signal_handlers();
    auto last_checkpoint = std::chrono::steady_clock::now();
    // A checkpoint that cannot be written (disk full, folder gone) costs the resume, not the
    // run: a warning, once, and the run goes on to write its results.
    bool checkpoint_warned = false;
    auto write_checkpoint = [&](const Simulation& s) {
      last_checkpoint = std::chrono::steady_clock::now();
      try {
        write_file_atomic(checkpoint_path, s.checkpoint());
      } catch (const std::exception& e) {
        if (!checkpoint_warned) std::fprintf(stderr, "ravel: warning: no checkpoint written: %s\n", e.what());
        checkpoint_warned = true;
      }
    };
#ifdef RAVEL_HAVE_SNAPSHOT
    auto recorder = render::FrameRecorder::create(rec, &rec_error);
    if (!recorder) throw OutputError(rec_error);
    bool rec_ok = recorder->on_sample(sim, &rec_error);  // the initial state
#endif
    inject_test_fault(sim);
    // Progress: on a terminal a line that rewrites itself 5 times a second; without one
    // (a log, CI) a line every 5 s. Percent and time left of the end time; an auto end
    // runs until perforation, rebound or caught, so it shows the cap it will not pass.
    const bool wanted = scene.output.progress && !has_switch(a, "quiet");
    const bool tty = isatty(fileno(stderr));
    const bool progress = wanted && tty;
    const auto started = std::chrono::steady_clock::now();
    auto last = started;
    const double end_s = scene.solver.end_time_s;
    // The run's loop (Simulation::run's, with the checkpoints): a step at a time; after each
    // history sample the frames and the progress line; at Ctrl-C a checkpoint of the state as
    // it is, before the run is marked interrupted.
    auto on_sample = [&](const Simulation& s) {
#ifdef RAVEL_HAVE_SNAPSHOT
      if (rec_ok) rec_ok = recorder->on_sample(s, &rec_error);
#endif
      if (checkpoint_every_s > 0 &&
          std::chrono::steady_clock::now() - last_checkpoint > std::chrono::duration<double>(checkpoint_every_s))
        write_checkpoint(s);
      if (!wanted) return;
      auto now = std::chrono::steady_clock::now();
      if (now - last < std::chrono::milliseconds(tty ? 200 : 5000)) return;
      last = now;
      const auto& r = s.history().back();
      const double wall = std::chrono::duration<double>(now - started).count();
      const double frac = end_s > 0 ? std::min(1.0, r.t_s / end_s) : 0.0;
      char when[96];
      if (scene.solver.end_time_auto)
        std::snprintf(when, sizeof when, "%.0f us/s simulated, until it decides (at most %.0f us)",
                      wall > 0 ? r.t_s * 1e6 / wall : 0.0, end_s * 1e6);
      else
        std::snprintf(when, sizeof when, "%3.0f %%, about %.0f s left", 100 * frac,
                      frac > 0 ? wall * (1 - frac) / frac : 0.0);
      std::fprintf(stderr,
                   tty ? "\r  t = %7.2f us  v = %7.2f m/s  broken %d/%d  %s   "
                       : "ravel: t = %.2f us, v = %.2f m/s, broken %d/%d, %s\n",
                   r.t_s * 1e6, r.projectile_velocity_mps, r.broken_warp, r.broken_weft, when);
    };
    std::size_t seen = sim.history().size();
    while (!sim.finished()) {
      if (g_interrupt.load()) {
        if (checkpoint_every_s > 0) write_checkpoint(sim);
        sim.interrupt("interrupted by signal");
        break;
      }
      sim.step();
      if (sim.history().size() != seen) {
        seen = sim.history().size();
        on_sample(sim);
      }
    }
    if (progress) std::fprintf(stderr, "\r%*s\r", 110, "");
    write_run_outputs(a.out_dir, sim);
    {
      // The run ended (or diverged): nothing to resume. Interrupted: the checkpoint stays.
      std::error_code ec;
      if (sim.summary().status != RunStatus::interrupted)
        std::filesystem::remove(checkpoint_path, ec);
      else if (std::filesystem::exists(checkpoint_path, ec) && !has_switch(a, "quiet"))
        std::printf("  checkpoint kept: %s (rerun with --resume to continue)\n", checkpoint_path.c_str());
    }
#ifdef RAVEL_HAVE_SNAPSHOT
    if (rec_ok) rec_ok = recorder->finish(sim, &rec_error);
    if (!rec_ok) throw OutputError(rec_error);
    if (recorder->images_written() && !has_switch(a, "quiet"))
      std::printf("  %d images in %s/frames/\n", recorder->images_written(), a.out_dir.c_str());
    if (recorder->vtk_written() && !has_switch(a, "quiet"))
      std::printf("  %d VTU frames in %s/vtk/frame.pvd\n", recorder->vtk_written(), a.out_dir.c_str());
#endif
    const Summary s = sim.summary();
    // "Model no more than a scene needs": a cheaper setting measured (ravel tradeoff,
    // assets/tradeoff/<scene>.json) to give the same answer within 1 % (docs/tradeoff.md).
    const auto suggestions = s.status == RunStatus::completed ? studies::shipped_tradeoff_suggestions(sim.scene())
                                                              : std::vector<std::string>{};
    studies::add_suggestions_to_summary(a.out_dir + "/summary.json", suggestions);
    print_summary_line(s, a.out_dir);
    for (const auto& t : suggestions) std::printf("  suggestion: %s\n", t.c_str());
    if (s.status == RunStatus::diverged) return exit_diverged;
    if (s.status == RunStatus::interrupted) return exit_interrupted;
    return exit_ok;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

int cmd_keys(const Args& args) {
  try {
    parse_args(args, "keys");  // no options: anything given is an error
  } catch (const std::exception& e) {
    return report_error(e);
  }
  std::printf("%-38s %-6s %-16s %-22s %s\n", "key", "unit", "default", "allowed", "meaning");
  for (const auto& k : scene_keys())
    std::printf("%-38s %-6s %-16s %-22s %s\n", k.key.c_str(), k.unit.c_str(), k.default_value.c_str(), k.range.c_str(),
                k.description.c_str());
  return 0;
}

}  // namespace ravel::app

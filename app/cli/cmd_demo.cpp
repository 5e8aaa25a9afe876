// `ravel demo --list` and `ravel demo NAME|all --out DIR [--quick] [--size WxH] [--threads N]
// [--quiet]`: the guided demos (app/demos/demos.h) rendered headless (OSMesa) as captioned PNGs
// of their key frames, their charts and DIR/index.md, for handouts and slides.
#include <atomic>
#include <cstdio>
#include <filesystem>

#include "cli.h"
#include "commands.h"
#include "demo_render.h"
#include "demos.h"

namespace ravel::app {

std::atomic<bool>& interrupt_flag();  // cmd_run.cpp
void install_signal_handlers();

int cmd_demo(const Args& args) {
  try {
    CommonArgs a = parse_args(args, "demo");
    const bool quick = has_switch(a, "quick");
    if (has_switch(a, "list") || a.scene_path.empty()) {
      std::printf("ravel demos (ravel demo NAME --out DIR; in the app: the Demos menu):\n\n");
      for (const demos::Demo& d : demos::catalogue(quick)) {
        std::printf("  %-9s %s\n            %s\n            key frames:", d.name.c_str(), d.title.c_str(),
                    d.summary.c_str());
        for (const auto& k : d.key_frames) {
          if (k.t_us < 0)
            std::printf(" end");
          else
            std::printf(" %g us", k.t_us);
        }
        std::printf("; runs:");
        for (const auto& r : d.runs) std::printf(" [%s]", r.label.c_str());
        std::printf("\n");
      }
      std::printf("\n  all       every demo, each into DIR/NAME/\n");
      if (!has_switch(a, "list") && a.scene_path.empty()) {
        std::fprintf(stderr, "ravel demo: name a demo (or 'all') and --out DIR\n");
        return exit_usage;
      }
      return exit_ok;
    }
    if (a.out_dir.empty()) throw UsageError("ravel demo: --out DIR is required");
    demos::DemoRenderOptions opt;
    opt.quick = quick;
    if (quick) {
      opt.width = 960;
      opt.height = 600;
    }
    if (a.flags.count("size")) {
      char x = 0, rest = 0;
      if (std::sscanf(a.flags["size"].c_str(), "%d%c%d%c", &opt.width, &x, &opt.height, &rest) != 3 || x != 'x' ||
          opt.width < 320 || opt.height < 240 || opt.width > 8192 || opt.height > 8192)
        throw UsageError("--size: expected WxH of at least 320x240, got '" + a.flags["size"] + "'");
    }
    if (a.threads >= 0) opt.solver_threads = a.threads;
    if (!has_switch(a, "quiet"))
      opt.progress = [](const std::string& s) {
        std::printf("%s\n", s.c_str());
        std::fflush(stdout);
      };

    std::vector<const demos::Demo*> selected;
    if (a.scene_path == "all") {
      for (const demos::Demo& d : demos::catalogue(quick)) selected.push_back(&d);
    } else {
      const demos::Demo* d = demos::find_demo(a.scene_path, quick);
      if (!d) {
        std::string names;
        for (const demos::Demo& x : demos::catalogue(quick)) names += (names.empty() ? "" : ", ") + x.name;
        throw UsageError("ravel demo: no demo '" + a.scene_path + "' (" + names + ", all; see ravel demo --list)");
      }
      selected.push_back(d);
    }
    // Ctrl-C stops the demo being rendered between steps; the demos already finished are kept
    // (each is whole once its index.md is written, last), and `ravel demo all` run again skips
    // them and renders the rest.
    install_signal_handlers();
    opt.interrupt = &interrupt_flag();
    int done = 0, skipped = 0;
    for (const demos::Demo* d : selected) {
      const std::string dir = selected.size() > 1 ? (std::filesystem::path(a.out_dir) / d->name).string() : a.out_dir;
      std::error_code ec;
      if (selected.size() > 1 && std::filesystem::exists(std::filesystem::path(dir) / "index.md", ec)) {
        if (opt.progress) opt.progress("demo " + d->name + ": finished earlier, kept (" + dir + ")");
        ++skipped;
        continue;
      }
      if (opt.progress) opt.progress("demo " + d->name + ": " + d->title + " -> " + dir);
      try {
        const demos::DemoResult r = demos::render_demo(*d, dir, opt);
        std::printf("demo %s: %zu key frames, %zu charts in %.0f s; see %s\n", d->name.c_str(), r.images.size(),
                    r.charts.size(), r.wall_time_s, r.index_path.c_str());
        ++done;
      } catch (const std::runtime_error& e) {
        if (!interrupt_flag().load()) throw;
        std::fprintf(stderr,
                     "ravel: interrupted during demo %s; finished demos kept: %d%s; run the same command again to "
                     "render the rest\n",
                     d->name.c_str(), done + skipped, selected.size() > 1 ? " (each with its index.md)" : "");
        return exit_interrupted;
      }
    }
    return exit_ok;
  } catch (const std::exception& e) {
    return report_error(e);
  }
}

}  // namespace ravel::app

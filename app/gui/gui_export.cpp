// Exports from the app: the run's results and scene, and the kept frames of the run (the
// timeline) as a ParaView series or as images of the 3D view (and a movie where ffmpeg is
// installed). The frame exports run a few frames per UI frame with a progress bar, so the
// app stays responsive; every file is written atomically.
#include <imgui.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "gui_app.h"
#include "gui_jobs.h"
#include "render/renderer.h"
#include "results.h"

namespace ravel::app::gui {

namespace {

void set_notice(GuiApp& app, const std::string& text, bool error) {
  app.notice = text;
  app.notice_is_error = error;
}

// Runs a program with these arguments (no shell, so no quoting of paths), its output
// discarded. Returns its exit status, 127 when it cannot be started.
int run_program(const std::vector<std::string>& argv) {
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) return 127;
  if (pid == 0) {
    // Only async-signal-safe calls between fork and exec (the app has other threads).
    const int null = open("/dev/null", O_WRONLY);
    if (null >= 0) dup2(null, 1), dup2(null, 2);
    execvp(args[0], args.data());
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return 127;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

// The files an earlier export left in the folder (frame_*.png, frame_*.vtu, frame.pvd,
// movie.mp4): removed so that the folder holds this export only.
void clear_old_frames(const std::string& dir) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string(), ext = e.path().extension().string();
    if ((name.rfind("frame_", 0) == 0 && (ext == ".png" || ext == ".vtu")) || name == "frame.pvd" ||
        name == "movie.mp4")
      std::filesystem::remove(e.path(), ec);
  }
}

std::vector<double> kept_times(const Timeline& tl) {
  std::vector<double> t;
  for (std::size_t i = 0; i < tl.size(); ++i) t.push_back(tl.time(i));
  return t;
}

bool start_job(GuiApp& app, ExportJob::Kind kind, const std::string& dir) {
  if (export_running(app)) {
    set_notice(app, "an export is running; wait for it to finish", true);
    return false;
  }
  if (app.timeline.empty()) {
    set_notice(app, "nothing to export: no frames kept yet (play the run first)", true);
    return false;
  }
  try {
    prepare_output_dir(dir);
  } catch (const std::exception& e) {
    set_notice(app, std::string("export failed: ") + e.what(), true);
    return false;
  }
  clear_old_frames(dir);
  auto job = std::make_unique<ExportJob>();
  job->kind = kind;
  job->dir = dir;
  job->run_id = app.view.run_id;
  job->times = kept_times(app.timeline);
  job->total = job->times.size();
  job->camera = app.camera;
  job->options = app.view_options;
  job->options.render_scale = 1.0f;
  job->options.ui_scale = std::max(2.0f, std::round(2.0f * app.ui_scale));
  job->width = std::max(16, int(app.view_w * app.ui_scale)) & ~1;  // even sizes for video encoders
  job->height = std::max(16, int(app.view_h * app.ui_scale)) & ~1;
  app.export_job = std::move(job);
  set_notice(app,
             std::string("exporting ") + std::to_string(app.export_job->total) +
                 (kind == ExportJob::Kind::vtk ? " frames as a VTK series into " : " frames as images into ") + dir +
                 " ...",
             false);
  return true;
}

}  // namespace

bool export_results(GuiApp& app) {
  try {
    prepare_output_dir(app.export_dir);
    std::string json = summary_json(app.view.summary, app.view.scene);
    // A run that has not ended is paused or still going: say which, not "running" for both.
    if (app.view.summary.status == RunStatus::running) {
      auto j = nlohmann::ordered_json::parse(json);
      j["status"] = app.view.state == WorkerState::running ? "running" : "paused";
      j["note"] = "exported from the app before the run ended: the outcome fields describe the run so far";
      json = j.dump(2) + "\n";
    }
    write_file_atomic(app.export_dir + "/history.csv", history_csv(app.view.history));
    write_file_atomic(app.export_dir + "/summary.json", json);
    set_notice(app, "wrote " + app.export_dir + "/history.csv and summary.json", false);
    return true;
  } catch (const std::exception& e) {
    set_notice(app, "export to the folder " + app.export_dir + " failed: " + e.what(), true);
    return false;
  }
}

bool export_scene(GuiApp& app) {
  try {
    prepare_output_dir(app.export_dir);
    const std::string path = app.export_dir + "/" + safe_file_name(app.view.scene.name) + ".toml";
    write_file_atomic(path, scene_to_toml(app.view.scene));
    set_notice(app, "wrote " + path + " (open it with: ravel gui " + path + ")", false);
    return true;
  } catch (const std::exception& e) {
    set_notice(app, "export to the folder " + app.export_dir + " failed: " + e.what(), true);
    return false;
  }
}

bool start_vtk_export(GuiApp& app, const std::string& dir) {
  return start_job(app, ExportJob::Kind::vtk, dir);
}

bool start_image_export(GuiApp& app, const std::string& dir) {
  return start_job(app, ExportJob::Kind::images, dir);
}

bool export_running(const GuiApp& app) {
  return app.export_job && !app.export_job->done;
}

void step_export(GuiApp& app, render::Renderer& renderer, int, int) {
  if (!export_running(app)) return;
  ExportJob& j = *app.export_job;
  if (app.view.run_id != j.run_id) {
    j.error = "the run was restarted during the export; " + std::to_string(j.written) + " of " +
              std::to_string(j.total) + " frames written";
    j.done = true;
  }
  const auto& times = j.times;
  const int per_frame = j.kind == ExportJob::Kind::vtk ? 4 : 1;
  for (int k = 0; k < per_frame && !j.done && j.next < j.total; ++k, ++j.next) {
    const std::size_t i = app.timeline.index_at(times[j.next]);
    if (app.timeline.time(i) != times[j.next]) continue;  // thinned away meanwhile
    const Frame f = app.timeline.frame(i);
    char name[64];
    std::string error;
    if (j.kind == ExportJob::Kind::vtk) {
      std::snprintf(name, sizeof name, "frame_%05zu.vtu", j.written);
      if (!write_vtu(f, j.dir + "/" + name, true, &error)) {
        j.error = error;
        j.done = true;
        break;
      }
      j.entries.push_back({f.time_s, name});
      ++j.written;
      if (!write_pvd(j.dir + "/frame.pvd", j.entries, &error)) {
        j.error = error;
        j.done = true;
      }
    } else {
      j.target.resize(j.width, j.height);
      j.target.bind();
      renderer.draw(f, j.camera, j.options, 0, 0, j.width, j.height);
      render::RenderTarget::bind_window();
      // Numbered by images written, so that the series has no gaps for ffmpeg's pattern.
      std::snprintf(name, sizeof name, "frame_%05zu.png", j.written);
      if (!render::write_png(j.dir + "/" + name, j.width, j.height, j.target.read_rgb(), &error)) {
        j.error = error;
        j.done = true;
      } else {
        ++j.written;
      }
    }
  }
  if (!j.done && j.next >= j.total) {
    j.done = true;
    if (j.kind == ExportJob::Kind::images) {
      j.target.release();
      const std::string out = j.dir + "/movie.mp4", tmp = j.dir + "/.movie.tmp.mp4";
      const int rc =
          run_program({"ffmpeg", "-y", "-loglevel", "error", "-framerate", "24", "-i", j.dir + "/frame_%05d.png",
                       "-pix_fmt", "yuv420p", "-vcodec", "libx264", "-f", "mp4", tmp});
      std::error_code ec;
      if (rc == 0) {
        std::filesystem::rename(tmp, out, ec);
        if (!ec)
          j.mp4 = out;
        else
          j.mp4_status = "the movie could not be renamed into place: " + ec.message();
      } else {
        j.mp4_status = rc == 127 ? "no ffmpeg: no movie" : "ffmpeg failed (exit " + std::to_string(rc) + "): no movie";
      }
      std::filesystem::remove(tmp, ec);
    }
  }
  if (j.done) {
    if (!j.error.empty()) {
      set_notice(app, "export into " + j.dir + " failed: " + j.error, true);
    } else if (j.kind == ExportJob::Kind::vtk) {
      set_notice(app, "wrote " + std::to_string(j.written) + " frames: " + j.dir + "/frame.pvd (ParaView)", false);
    } else {
      set_notice(app,
                 "wrote " + std::to_string(j.written) + " images into " + j.dir +
                     (j.mp4.empty() ? " (" + j.mp4_status + ")" : ", and " + j.mp4),
                 false);
    }
    std::printf("ravel gui: %s\n", app.notice.c_str());
    std::fflush(stdout);
  }
}

void draw_export_progress(GuiApp& app) {
  if (!export_running(app)) return;
  const ExportJob& j = *app.export_job;
  const float fs = ImGui::GetFontSize();
  ImGui::SetNextWindowPos(ImVec2(app.view_x + app.view_w * 0.5f, app.view_y + fs * 3), ImGuiCond_Always,
                          ImVec2(0.5f, 0));
  ImGui::SetNextWindowBgAlpha(0.9f);
  ImGui::Begin("##export", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings);
  ImGui::Text("%s into %s", j.kind == ExportJob::Kind::vtk ? "VTK series" : "images", j.dir.c_str());
  char label[64];
  std::snprintf(label, sizeof label, "%zu / %zu frames", j.next, j.total);
  ImGui::ProgressBar(j.total ? float(j.next) / float(j.total) : 0.0f, ImVec2(fs * 20, 0), label);
  if (ImGui::Button("Cancel")) {
    app.export_job->error = "cancelled";
    app.export_job->done = true;
    set_notice(app, "export into " + j.dir + " cancelled after " + std::to_string(j.next) + " frames", true);
  }
  ImGui::End();
}

}  // namespace ravel::app::gui

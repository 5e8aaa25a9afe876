// Headless demo pictures: split viewports, theory overlays, caption banner, charts, index.md.
#include "demo_render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace ravel::app::demos {

namespace fs = std::filesystem;

// Colours no colour map of the renderer uses (turbo, viridis), so the lines can be found
// on the image: magenta and white.
render::Vec3 longitudinal_color() {
  return {1.0f, 0.3f, 0.95f};
}
render::Vec3 transverse_color() {
  return {1.0f, 1.0f, 1.0f};
}

ImageLayout layout_image(int w, int h, const std::vector<Frame>& first_frames, render::ViewPreset view, bool chart) {
  ImageLayout L;
  L.width = w;
  L.height = h;
  const float s = render::Annotator::default_scale(h);
  L.banner_h = int(std::ceil(2 * 11 * s - 4 * s + 12 * s + 10 * s));
  L.banner_y = h - L.banner_h;
  L.chart_h = chart ? int(0.30 * h) : 0;
  L.chart_y = L.banner_y - L.chart_h;
  const int n = int(first_frames.size());
  const int cols = n == 4 ? 2 : std::max(1, n), rows = n == 4 ? 2 : 1;
  const int area_h = L.chart_y, gap = n > 1 ? 4 : 0;
  for (int i = 0; i < n; ++i) {
    ViewportLayout v;
    const int c = i % cols, r = i / cols;
    v.x = c * w / cols + (c > 0 ? gap / 2 : 0);
    v.w = (c + 1) * w / cols - c * w / cols - (n > 1 ? gap / 2 : 0);
    v.y = r * area_h / rows + (r > 0 ? gap / 2 : 0);
    v.h = (r + 1) * area_h / rows - r * area_h / rows - (rows > 1 ? gap / 2 : 0);
    v.camera = render::fitted_camera(first_frames[i], view, float(v.w) / float(std::max(1, v.h)));
    // Side by side the viewports are narrow: come closer, the fabric's middle is what matters.
    if (n > 1 && view != render::ViewPreset::top) v.camera.zoom(0.72f);
    L.viewports.push_back(v);
  }
  return L;
}

std::vector<render::WorldPolyline> wave_front_lines(const Scene& scene, const Frame& frame, double t_s) {
  const WaveFronts f = wave_fronts(scene, t_s);
  const float cx = float(scene.projectile.offset_x_m), cy = float(scene.projectile.offset_y_m);
  const float hw = frame.half_width_m, hl = frame.half_length_m;
  // The fabric's mid-plane height at rest (z of the nodes, averaged).
  float z = 0;
  if (!frame.node_pos.empty()) {
    double sum = 0;
    for (const auto& p : frame.node_pos) sum += p[2];
    z = float(sum / double(frame.node_pos.size()));
  }
  auto diamond = [&](double r, render::Vec3 color, const std::string& label) {
    render::WorldPolyline line;
    line.color = color;
    line.closed = true;
    line.width_px = 2.5f;
    // Walk the diamond |x - cx| + |y - cy| = r, clipped to the fabric's rectangle.
    const int n = 256;
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      // A point on the diamond in direction a: scale the unit vector so |x| + |y| = r.
      const double ux = std::cos(a), uy = std::sin(a), k = r / (std::abs(ux) + std::abs(uy));
      const float x = std::clamp(float(cx + k * ux), -hw, hw), y = std::clamp(float(cy + k * uy), -hl, hl);
      line.points.push_back({x, y, z});
    }
    line.label = label;
    line.label_at = {std::min(float(cx + r), hw), cy, z};
    return line;
  };
  std::vector<render::WorldPolyline> out;
  char b[96];
  // A front that has left the fabric is not drawn (it reflected at the edges).
  const double reach = std::max(hw + std::abs(cx), hl + std::abs(cy));
  if (f.longitudinal_m > 0 && f.longitudinal_m < reach) {
    std::snprintf(b, sizeof b, "c t = %.1f mm", f.longitudinal_m * 1e3);
    out.push_back(diamond(f.longitudinal_m, longitudinal_color(), b));
  }
  if (f.transverse_m > 0 && f.transverse_m < reach) {
    std::snprintf(b, sizeof b, "U t = %.1f mm", f.transverse_m * 1e3);
    auto t = diamond(f.transverse_m, transverse_color(), b);
    t.label_at = {float(cx), std::min(float(cy + f.transverse_m), hl), z};
    out.push_back(t);
  }
  return out;
}

studies::Chart velocity_chart(const Demo& demo, const std::vector<RunState>& runs, double x_max_us) {
  studies::Chart c;
  c.title = "Projectile velocity";
  c.subtitle = demo.title + ": " + demo.note;
  c.x = {"time", "us", true, 0, std::max(1.0, x_max_us), false};
  double vmax = 0, vmin = 0;
  for (const RunState& r : runs) vmax = std::max(vmax, r.summary.impact_velocity_mps);
  for (const RunState& r : runs)
    for (const HistoryRow& h : r.history) vmin = std::min(vmin, h.projectile_velocity_mps);
  (void)vmin;
  (void)vmax;
  c.y = {"projectile speed along the flight path", "m/s", false, 0, 1, false};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    studies::Series s;
    s.name = runs[i].label;
    s.style = studies::SeriesStyle::line;
    s.color = int(i);
    for (const HistoryRow& h : runs[i].history) {
      s.x.push_back(h.t_s * 1e6);
      s.y.push_back(h.projectile_velocity_mps);
    }
    c.series.push_back(std::move(s));
  }
  return c;
}

studies::Chart broken_chart(const Demo& demo, const std::vector<RunState>& runs) {
  studies::Chart c;
  c.title = "Broken yarn elements per direction";
  c.subtitle = demo.title + ": weft (along x, clamped) solid, warp (along y, free) dashed";
  c.x = {"time", "us", false, 0, 1, true};
  c.y = {"broken elements (whole fabric)", "", false, 0, 1, true};
  for (std::size_t i = 0; i < runs.size(); ++i) {
    for (int fam = 0; fam < 2; ++fam) {
      studies::Series s;
      s.name = runs[i].label + (fam == 0 ? ", weft" : ", warp");
      s.style = studies::SeriesStyle::line;
      s.color = int(i);
      s.dashed = fam == 1;
      for (const HistoryRow& h : runs[i].history) {
        s.x.push_back(h.t_s * 1e6);
        s.y.push_back(fam == 0 ? h.broken_weft : h.broken_warp);
      }
      c.series.push_back(std::move(s));
    }
  }
  return c;
}

namespace {

render::ViewOptions demo_view_options(const Demo& demo, const ImageLayout& L) {
  render::ViewOptions o;
  render::parse_view_preset(demo.view, &o.view);
  render::parse_color_field(demo.field, &o.field);
  if (demo.range_max > 0) {
    o.range_min = 0;
    o.range_max = demo.range_max;
  }
  o.ui_scale = render::Annotator::default_scale(L.height);
  if (L.viewports.size() > 2) o.ui_scale = std::max(1.0f, o.ui_scale - 0.0f);
  return o;
}

bool has_chart(const Demo& demo, DemoChart c) {
  return std::find(demo.charts.begin(), demo.charts.end(), c) != demo.charts.end();
}

std::string time_tag(double t_us) {
  char b[32];
  if (std::abs(t_us - std::round(t_us)) < 0.05)
    std::snprintf(b, sizeof b, "%.0fus", t_us);
  else
    std::snprintf(b, sizeof b, "%.1fus", t_us);
  return b;
}

}  // namespace

std::vector<std::uint8_t> compose_key_frame(render::HeadlessRenderer& hr, render::Annotator& annotator,
                                            const Demo& demo, const std::vector<std::string>& caption_lines,
                                            const std::vector<RunState>& runs, const ImageLayout& L,
                                            double chart_x_max_us) {
  render::OffscreenContext& ctx = hr.context();
  if (!ctx.resize(L.width, L.height)) throw std::runtime_error("cannot make an offscreen image");
  // The whole image: the background gradient only (it clears the rectangle first).
  render::ViewOptions bg;
  bg.show_fabric = bg.show_projectile = bg.show_clamps = bg.show_caption = bg.show_colorbar = false;
  bg.show_scale_bar = bg.show_axes = false;  // (they belong to the viewports, not under the banner)
  bg.background_top = {0.13f, 0.15f, 0.19f};
  bg.background_bottom = {0.06f, 0.07f, 0.09f};
  if (!runs.empty())
    hr.renderer().draw(runs[0].frame, L.viewports.empty() ? render::Camera{} : L.viewports[0].camera, bg, 0, 0, L.width,
                       L.height);
  render::ViewOptions o = demo_view_options(demo, L);
  std::vector<const Frame*> frames;
  for (const RunState& r : runs) frames.push_back(&r.frame);
  render::share_field_range(frames, &o);  // one colour bar for every run
  for (std::size_t i = 0; i < runs.size() && i < L.viewports.size(); ++i) {
    const ViewportLayout& v = L.viewports[i];
    const int gl_y = L.height - v.y - v.h;
    render::ViewOptions oi = o;
    oi.show_colorbar = i + 1 == runs.size();  // one colour bar, in the last viewport
    hr.renderer().draw(runs[i].frame, v.camera, oi, v.x, gl_y, v.w, v.h);
    std::vector<render::WorldPolyline> lines;
    if (demo.overlay == Overlay::wave_fronts) {
      const Scene s = demo_scene(demo, i);
      lines = wave_front_lines(s, runs[i].frame, runs[i].frame.time_s);
    }
    // The run's name bottom right, above the scale bar's row (bottom left when the wave
    // fronts' legend takes that corner).
    const bool legend = demo.overlay == Overlay::wave_fronts;
    render::TextBlock title;
    title.x = legend ? 10 : -10;
    title.y = legend ? -10 : -(10 + 32 * o.ui_scale);
    title.lines = {runs[i].label};
    title.colors = {render::Vec3{1.0f, 0.75f, 0.35f}};
    title.scale = render::Annotator::default_scale(L.height) + 1;
    std::vector<render::TextBlock> texts = {title};
    if (demo.overlay == Overlay::wave_fronts) {
      render::TextBlock legend;
      legend.x = -10;
      legend.y = -10;
      legend.lines = {"theory (single straight yarn):", "longitudinal front, c t", "transverse front, U t (Smith)"};
      legend.colors = {render::Vec3{0.85f, 0.87f, 0.9f}, longitudinal_color(), transverse_color()};
      texts.push_back(legend);
    }
    annotator.draw(v.camera, lines, texts, v.x, gl_y, v.w, v.h);
  }
  // Caption banner across the bottom: the two lines, then what is shown.
  render::TextBlock banner;
  banner.x = 0;
  banner.y = 0;
  banner.min_width_px = float(L.width);
  banner.lines = caption_lines;
  banner.colors = {render::Vec3{1.0f, 1.0f, 1.0f}, render::Vec3{1.0f, 1.0f, 1.0f}};
  banner.scale = render::Annotator::default_scale(L.height);
  annotator.draw(render::Camera{}, {}, {banner}, 0, 0, L.width, L.banner_h);
  std::vector<std::uint8_t> rgb = ctx.read_rgb();
  if (L.chart_h > 0 && !runs.empty()) {
    studies::Chart c = velocity_chart(demo, runs, chart_x_max_us);
    c.subtitle.clear();
    const int cw = L.width, ch = L.chart_h;
    const std::vector<unsigned char> img = studies::chart_rgb(c, cw, ch);
    for (int y = 0; y < ch; ++y)
      std::copy_n(img.begin() + long(y) * cw * 3, std::size_t(cw) * 3,
                  rgb.begin() + (long(L.chart_y + y) * L.width) * 3);
  }
  return rgb;
}

DemoResult render_demo(const Demo& demo, const std::string& out_dir, const DemoRenderOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  auto say = [&](const std::string& s) {
    if (opt.progress) opt.progress(s);
  };
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec || !fs::is_directory(out_dir)) throw std::runtime_error("cannot create the folder " + out_dir);
  std::string error;
  auto hr = render::HeadlessRenderer::create(&error);
  if (!hr) throw std::runtime_error("no offscreen OpenGL context (OSMesa): " + error);
  hr->context().make_current();
  render::Annotator annotator;

  DemoRunner runner(demo, opt.solver_threads, opt.interrupt);
  std::vector<Frame> first;
  for (std::size_t i = 0; i < runner.size(); ++i) first.push_back(runner.simulation(i).frame());
  render::ViewPreset view = render::ViewPreset::oblique;
  render::parse_view_preset(demo.view, &view);
  const bool chart_strip = has_chart(demo, DemoChart::velocity_history) && runner.size() > 1;
  const ImageLayout layout = layout_image(opt.width, opt.height, first, view, chart_strip);

  DemoResult result;
  for (std::size_t k = 0; k < demo.key_frames.size(); ++k) {
    const KeyFrame& key = demo.key_frames[k];
    const auto w0 = std::chrono::steady_clock::now();
    if (key.t_us < 0)
      runner.run_to_end();
    else
      runner.advance_to(key.t_us * 1e-6);
    DemoImage img;
    img.runs = runner.state();
    double t_show = 0;
    for (const RunState& r : img.runs) t_show = std::max(t_show, r.frame.time_s * 1e6);
    if (key.t_us >= 0) t_show = key.t_us;
    img.t_us = t_show;
    img.caption = caption(demo, key, img.runs);
    img.layout = layout;
    char name[160];
    std::snprintf(name, sizeof name, "%02d_%s_%s.png", int(k + 1), demo.name.c_str(), time_tag(t_show).c_str());
    img.path = (fs::path(out_dir) / name).string();
    say("  " + demo.name + ": key frame " + std::to_string(k + 1) + "/" + std::to_string(demo.key_frames.size()) +
        " at " + time_tag(t_show) + " (simulated in " +
        std::to_string(int(std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count())) + " s)");
    result.images.push_back(std::move(img));
  }
  // Let every run finish for the charts (the last key frame is usually the end already).
  runner.run_to_end();
  const std::vector<RunState> final_state = runner.state();
  double t_end_us = 0;
  for (const RunState& r : final_state) t_end_us = std::max(t_end_us, r.frame.time_s * 1e6);

  for (DemoImage& img : result.images) {
    const std::vector<std::uint8_t> rgb =
        compose_key_frame(*hr, annotator, demo, img.caption, img.runs, img.layout, t_end_us);
    if (!render::write_png(img.path, layout.width, layout.height, rgb, &error))
      throw std::runtime_error("cannot write " + img.path + ": " + error);
    say("  wrote " + img.path);
  }
  for (DemoChart c : demo.charts) {
    const std::string stem =
        (fs::path(out_dir) / (demo.name + (c == DemoChart::velocity_history ? "_velocity" : "_broken"))).string();
    studies::write_chart(c == DemoChart::velocity_history ? velocity_chart(demo, final_state, t_end_us)
                                                          : broken_chart(demo, final_state),
                         stem);
    result.charts.push_back(stem);
    say("  wrote " + stem + ".png/.svg/.csv");
  }
  // index.md
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::string md = "# ravel demo: " + demo.title + "\n\n" + demo.summary + ".\n\n";
  md += "- Scene: `" + demo.scene + "`";
  for (const auto& o : demo.overrides) md += " `" + o + "`";
  md += "\n- Runs:";
  for (std::size_t i = 0; i < demo.runs.size(); ++i) {
    md += "\n  - **" + demo.runs[i].label + "**:";
    for (const auto& o : demo.runs[i].overrides) md += " `" + o + "`";
    const Summary& s = final_state[i].summary;
    char b[256];
    std::snprintf(b, sizeof b, " %s at %.1f us, exit speed %.0f m/s, broken yarns %d weft (clamped) / %d warp (free)",
                  s.perforated ? "perforated" : "not perforated", final_state[i].frame.time_s * 1e6,
                  s.residual_velocity_mps, s.broken_weft_yarns, s.broken_warp_yarns);
    md += b;
  }
  md += "\n- Note: " + demo.note + "\n";
  if (opt.quick)
    md += "- **Quick mode** (tests): a 50 x 50 mm ply and short runs; the pictures check the tool, not the physics.\n";
  char b[128];
  std::snprintf(b, sizeof b, "- Made with `ravel demo %s%s` in %.0f s.\n\n## Key frames\n\n", demo.name.c_str(),
                opt.quick ? " --quick" : "", result.wall_time_s);
  md += b;
  for (const DemoImage& img : result.images) {
    const std::string file = fs::path(img.path).filename().string();
    md += "### " + time_tag(img.t_us) + "\n\n![" + file + "](" + file + ")\n\n> " + img.caption[0] + "  \n> " +
          img.caption[1] + "\n\n";
  }
  if (!result.charts.empty()) {
    md += "## Charts\n\n";
    for (const auto& stem : result.charts) {
      const std::string f = fs::path(stem).filename().string();
      md += "![" + f + "](" + f + ".png) ([SVG](" + f + ".svg), [CSV](" + f + ".csv))\n\n";
    }
  }
  result.index_path = (fs::path(out_dir) / "index.md").string();
  const std::string tmp = result.index_path + ".tmp";
  {
    std::ofstream f(tmp);
    f << md;
    if (!f) throw std::runtime_error("cannot write " + result.index_path);
  }
  fs::rename(tmp, result.index_path, ec);
  if (ec) throw std::runtime_error("cannot write " + result.index_path);
  return result;
}

}  // namespace ravel::app::demos

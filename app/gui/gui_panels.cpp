// The app's panels: run controls, scene editor, view, export, charts, status.
#include <imgui.h>
#include <imgui_internal.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>

#include "gui_app.h"
#include "gui_charts.h"
#include "gui_jobs.h"
#include "results.h"
#ifdef RAVEL_HAVE_STUDIES_IMGUI
#include <atomic>
#include <cstdlib>
#include <thread>

#include "chart_imgui.h"
#include "stability.h"
#endif

namespace ravel::app::gui {

void help_marker(const char* text) {
  ImGui::SameLine();
  ImGui::TextDisabled("(?)");
  if (ImGui::IsItemHovered()) {
    ImGui::BeginTooltip();
    ImGui::PushTextWrapPos(ImGui::GetFontSize() * 28.0f);
    ImGui::TextUnformatted(text);
    ImGui::PopTextWrapPos();
    ImGui::EndTooltip();
  }
}

namespace {

// The fixed panels draw no background of their own: the window is cleared to the same
// colour (ImGuiCol_WindowBg) every frame, and under a software GL (llvmpipe) a blended
// rectangle over the whole panel area costs several milliseconds per frame.
constexpr ImGuiWindowFlags kFixedPanel = ImGuiWindowFlags_NoBackground;

const ImVec4 kAccent(0.95f, 0.62f, 0.20f, 1.0f);
const ImVec4 kGood(0.45f, 0.85f, 0.45f, 1.0f);
const ImVec4 kWarn(1.0f, 0.80f, 0.30f, 1.0f);
const ImVec4 kBad(1.0f, 0.42f, 0.38f, 1.0f);

// A double kept in SI, edited in display units (display = si * scale).
bool slider_si(const char* label, double* si, double scale, double lo, double hi, const char* fmt, bool log = false) {
  double v = *si * scale;
  const bool changed =
      ImGui::SliderScalar(label, ImGuiDataType_Double, &v, &lo, &hi, fmt, log ? ImGuiSliderFlags_Logarithmic : 0);
  if (changed) *si = v / scale;
  return changed;
}

bool input_si(const char* label, double* si, double scale, const char* fmt) {
  double v = *si * scale;
  const bool changed = ImGui::InputDouble(label, &v, 0, 0, fmt, ImGuiInputTextFlags_EnterReturnsTrue);
  if (changed) *si = v / scale;
  return changed;
}

// The run-relevant text of a scene, to tell whether the draft differs from the run.
std::string run_key(Scene s) {
  s.solver.threads = 0;  // applied live, not a restart
  s.warnings.clear();
  s.source.clear();
  return scene_to_toml(s);
}

// The layout check (RAVEL_LAYOUT_CHECK, GuiApp::layout_check) opens every section and tree
// node, so every control is laid out and measured.
bool header(const GuiApp& app, const char* label, ImGuiTreeNodeFlags flags = 0) {
  if (app.layout_check) ImGui::SetNextItemOpen(true, ImGuiCond_Always);
  return ImGui::CollapsingHeader(label, flags);
}
bool tree_node(const GuiApp& app, const char* label) {
  if (app.layout_check) ImGui::SetNextItemOpen(true, ImGuiCond_Always);
  return ImGui::TreeNode(label);
}

bool accent_button(const char* label, bool accent, ImVec2 size = ImVec2(0, 0)) {
  if (accent) {
    ImGui::PushStyleColor(ImGuiCol_Button, ImVec4(0.78f, 0.45f, 0.10f, 1.0f));
    ImGui::PushStyleColor(ImGuiCol_ButtonHovered, ImVec4(0.90f, 0.55f, 0.15f, 1.0f));
    ImGui::PushStyleColor(ImGuiCol_ButtonActive, ImVec4(0.98f, 0.62f, 0.20f, 1.0f));
  }
  const bool pressed = ImGui::Button(label, size);
  if (accent) ImGui::PopStyleColor(3);
  return pressed;
}

// The label with its key hint if it fits the width, else without it.
std::string fit_label(const char* text, const char* hint, float width) {
  const std::string with = std::string(text) + "  " + hint;
  const float pad = 2 * ImGui::GetStyle().FramePadding.x;
  return ImGui::CalcTextSize(with.c_str()).x + pad <= width ? with : std::string(text);
}

void run_controls(GuiApp& app) {
  SimWorker& w = *app.worker;
  const float fs = ImGui::GetFontSize();
  const float full = ImGui::GetContentRegionAvail().x;
  const float third = (full - 2 * ImGui::GetStyle().ItemSpacing.x) / 3;
  // The buttons say what the run is doing: a finished or diverged run can only be reset or
  // restarted (Play and Step are disabled, neither highlighted).
  const bool ended = app.view.state == WorkerState::finished || app.view.state == WorkerState::diverged;
  if (ended) {
    ImGui::BeginDisabled();
    ImGui::Button(fit_label("Play", "[Space]", third).c_str(), ImVec2(third, 0));
    ImGui::EndDisabled();
    if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
      ImGui::SetTooltip(app.view.state == WorkerState::diverged ? "The run diverged: Reset, or Restart with new values"
                                                                : "The run has ended: Reset or Restart");
  } else if (app.view.state != WorkerState::running) {
    if (accent_button(fit_label("Play", "[Space]", third).c_str(), true, ImVec2(third, 0))) w.play();
  } else if (ImGui::Button(fit_label("Pause", "[Space]", third).c_str(), ImVec2(third, 0))) {
    w.pause();
  }
  ImGui::SameLine();
  ImGui::BeginDisabled(ended);
  if (ImGui::Button(fit_label("Step", "[S]", third).c_str(), ImVec2(third, 0))) w.step_once(1);
  ImGui::EndDisabled();
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Pause and advance one time step [S]");
  ImGui::SameLine();
  if (ImGui::Button(fit_label("Reset", "[R]", third).c_str(), ImVec2(third, 0))) w.reset();
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Back to t = 0 with the scene that is running [R]");

  const bool dirty = run_key(app.draft) != run_key(app.view.scene);
  if (accent_button(fit_label(dirty ? "Restart with new values" : "Restart", "[Enter]", full).c_str(), dirty,
                    ImVec2(full, 0)))
    restart_with_draft(app);
  if (dirty) ImGui::TextColored(kAccent, "Edited values are not running yet.");
  ImGui::Checkbox("Restart on every change", &app.auto_restart);
  help_marker(
      "What-if mode: each edit in the panels below restarts the run at once. "
      "The run it replaces stays in the charts as a faint overlay.");

  ImGui::Spacing();
  bool pacing_changed = false;
  if (ImGui::RadioButton("As fast as possible", app.pacing.max_speed)) {
    app.pacing.max_speed = true;
    pacing_changed = true;
  }
  ImGui::SameLine();
  if (ImGui::RadioButton("Slow motion", !app.pacing.max_speed)) {
    app.pacing.max_speed = false;
    pacing_changed = true;
  }
  ImGui::BeginDisabled(app.pacing.max_speed);
  ImGui::SetNextItemWidth(std::max(fs * 5, full - ImGui::CalcTextSize("\xC2\xB5s per second").x - fs));
  pacing_changed |= slider_si("\xC2\xB5s per second", &app.pacing.sim_us_per_wall_s, 1.0, 0.05, 50.0, "%.2f", true);
  ImGui::EndDisabled();
  if (pacing_changed) w.set_pacing(app.pacing);
  ImGui::SetNextItemWidth(std::max(fs * 5, full - ImGui::CalcTextSize("pause at \xC2\xB5s (?)").x - fs));
  double pause_at = app.pause_at_us;
  if (ImGui::InputDouble("pause at \xC2\xB5s", &pause_at, 0, 0, pause_at < 0 ? "off" : "%.2f",
                         ImGuiInputTextFlags_EnterReturnsTrue)) {
    app.pause_at_us = pause_at > 0 ? pause_at : -1;
    w.pause_at(app.pause_at_us > 0 ? app.pause_at_us * 1e-6 : -1);
  }
  help_marker("Pause the run when simulated time reaches this value (Enter to apply; 0 = off).");
}

bool scene_section(GuiApp& app) {
  Scene& s = app.draft;
  bool changed = false;
  if (!app.shipped_scenes.empty()) {
    std::string current = s.name;
    if (ImGui::BeginCombo("preset", current.c_str())) {
      for (const auto& path : app.shipped_scenes) {
        const std::string name = std::filesystem::path(path).stem().string();
        if (ImGui::Selectable(name.c_str(), name == s.name)) {
          try {
            app.draft = load_scene(path);
            changed = true;
          } catch (const std::exception& e) {
            app.scene_error = e.what();
          }
        }
      }
      ImGui::EndCombo();
    }
    help_marker("Fabric presets: the scenes shipped in assets/scenes. Loading one replaces every value below.");
  }
  changed |= slider_si("width (mm)", &s.fabric.width_m, 1e3, 5, 200, "%.1f");
  changed |= slider_si("length (mm)", &s.fabric.length_m, 1e3, 5, 200, "%.1f");
  help_marker(
      "Fabric size. Larger fabrics have more nodes and step more slowly "
      "(the default 120 x 120 mm is about 10,000 nodes in a quarter model).");
  // Clamped edges as a 2 x 2 grid, so they fit a narrow panel.
  ImGui::TextUnformatted("clamped edges");
  help_marker(
      "left / right: x = -W/2, +W/2 (they hold the weft yarns); bottom / top: y = -L/2, +L/2 (the warp yarns).");
  if (ImGui::BeginTable("clamps", 2)) {
    ImGui::TableNextColumn();
    changed |= ImGui::Checkbox("left", &s.fabric.clamped.left);
    ImGui::TableNextColumn();
    changed |= ImGui::Checkbox("right", &s.fabric.clamped.right);
    ImGui::TableNextColumn();
    changed |= ImGui::Checkbox("bottom", &s.fabric.clamped.bottom);
    ImGui::TableNextColumn();
    changed |= ImGui::Checkbox("top", &s.fabric.clamped.top);
    ImGui::EndTable();
  }
  int grip = s.fabric.clamp == ClampKind::rigid ? 0 : 1;
  if (ImGui::Combo("clamp", &grip, "rigid (paper)\0slips at a grip\0")) {
    s.fabric.clamp = grip == 0 ? ClampKind::rigid : ClampKind::slipping;
    changed = true;
  }
  help_marker(
      "Rigid: no yarn leaves a clamp (the paper). Slips at a grip: the clamp feeds yarn out once the yarn "
      "pulls harder than the grip, as in a test rig's clamp (fabric.clamp, docs/MODEL.md section 7).");
  ImGui::BeginDisabled(s.fabric.clamp == ClampKind::rigid);
  changed |= slider_si("grip (N/yarn)", &s.fabric.clamp_grip_n, 1, 10, 300, "%.0f");
  help_marker(
      "Pull on one yarn at which the clamp feeds it out (fabric.clamp_grip_n); the yarn breaks at about "
      "290 N, so a grip above that never slips.");
  changed |= slider_si("depth (mm)", &s.fabric.clamp_depth_m, 1e3, 5, 60, "%.0f");
  help_marker("Yarn the clamp holds (fabric.clamp_depth_mm): fed out past it, the yarn has left the clamp.");
  ImGui::EndDisabled();
  changed |= slider_si("failure strain (%)", &s.yarn.failure_strain, 100, 1.0, 10.0, "%.2f");
  int mat = s.yarn.material == Material::zener ? 0 : 1;
  if (ImGui::Combo("material", &mat, "Zener (viscoelastic)\0linear elastic\0")) {
    s.yarn.material = mat == 0 ? Material::zener : Material::elastic;
    changed = true;
  }
  if (tree_node(app, "Weave and crossings")) {
    changed |= input_si("L0 (mm)", &s.fabric.spacing_m, 1e3, "%.4g");
    help_marker("L0: horizontal node spacing, the yarn pitch (fabric.spacing_mm). Enter to apply.");
    changed |= input_si("L1 (mm)", &s.fabric.crossing_gap_m, 1e3, "%.4g");
    help_marker(
        "L1: vertical distance of the two nodes at a crossing, the crimp (fabric.crossing_gap_mm). Enter to apply.");
    changed |= input_si("thickness (mm)", &s.fabric.thickness_m, 1e3, "%.4g");
    help_marker("Fabric thickness; the yarn contact diameter D is half of it. Enter to apply.");
    changed |= input_si("node mass (g)", &s.fabric.node_mass_kg, 1e3, "%.4g");
    help_marker("Lumped mass of a yarn node (paper: 9.4e-5 g). Enter to apply.");
    changed |= ImGui::SliderInt("yarns/elem.", &s.fabric.yarns_per_element, 1, 8);
    help_marker("Lump k real yarns into one modelled yarn: a coarser, faster mesh that keeps the crimp angle.");
    ImGui::BeginDisabled(s.fabric.yarns_per_element > 1);
    changed |= ImGui::SliderInt("graded k", &s.fabric.far_yarns_per_element, 1, 8);
    help_marker(
        "Graded mesh (fabric.far_yarns_per_element): every yarn near the strike point and the clamps, k real yarns "
        "per modelled yarn elsewhere. About 3.5x faster at k = 3 and the same response until yarns break; not for "
        "ballistic limits (docs/tradeoff.md).");
    ImGui::BeginDisabled(s.fabric.far_yarns_per_element <= 1);
    changed |= slider_si("fine (mm)", &s.fabric.full_resolution_m, 1e3, 0, 60, "%.0f");
    help_marker("Half-width of the bands through the strike point modelled yarn by yarn (fabric.full_resolution_mm).");
    changed |= slider_si("at clamps (mm)", &s.fabric.clamp_resolution_m, 1e3, 0, 60, "%.0f");
    help_marker("Width of the bands along the clamps modelled yarn by yarn (fabric.clamp_resolution_mm).");
    ImGui::EndDisabled();
    ImGui::EndDisabled();
    int comp = s.fabric.crossing_compression == CrossingCompression::hyperbolic ? 0 : 1;
    if (ImGui::Combo("crossings", &comp, "flatten under load\0rigid (paper literally)\0")) {
      s.fabric.crossing_compression = comp == 0 ? CrossingCompression::hyperbolic : CrossingCompression::rigid;
      changed = true;
    }
    ImGui::BeginDisabled(s.fabric.crossing_compression != CrossingCompression::hyperbolic);
    changed |= slider_si("c_min (mm)", &s.fabric.flattened_gap_m, 1e3, 0.05, 0.2, "%.3f");
    help_marker(
        "c_min: centre distance of two fully flattened yarns (fabric.flattened_gap_mm, docs/MODEL.md section 4).");
    changed |= slider_si("F_half (N)", &s.fabric.compression_force_n, 1, 0.05, 20, "%.2f", true);
    help_marker(
        "F_half: normal force that closes half of the packing stage (fabric.compression_force_n, docs/MODEL.md "
        "section 4).");
    changed |= slider_si("c_pack (mm)", &s.fabric.packed_gap_m, 1e3, 0.05, 0.2, "%.3f");
    help_marker(
        "c_pack: centre distance once the fibres are packed, before they flatten (fabric.packed_gap_mm). At or below "
        "c_min the law has one stage (the default); above it, the last c_pack - c_min closes only at forces near "
        "F_flat (docs/MODEL.md section 4).");
    ImGui::BeginDisabled(s.fabric.packed_gap_m <= s.fabric.flattened_gap_m);
    changed |= slider_si("F_flat (N)", &s.fabric.flattening_force_n, 1, 1, 500, "%.0f", true);
    help_marker(
        "F_flat: normal force that closes half of the flattening stage c_pack - c_min "
        "(fabric.flattening_force_n).");
    ImGui::EndDisabled();
    ImGui::EndDisabled();
    ImGui::TreePop();
  }
  if (s.yarn.material == Material::zener && tree_node(app, "Zener constants")) {
    changed |= input_si("K1 (GPa)", &s.yarn.k1_pa, 1e-9, "%.2f");
    help_marker("Zener spring in series: the instantaneous modulus (Eq 23). Enter to apply.");
    changed |= input_si("K2 (GPa)", &s.yarn.k2_pa, 1e-9, "%.2f");
    help_marker("Zener spring of the Kelvin-Voigt unit (Eq 23). Enter to apply.");
    changed |= input_si("mu_d (MPa s)", &s.yarn.damping_pa_s, 1e-6, "%.1f");
    help_marker("Zener dashpot (Eq 23). Enter to apply.");
    ImGui::TreePop();
  } else if (s.yarn.material == Material::elastic) {
    changed |= input_si("E (GPa)", &s.yarn.modulus_pa, 1e-9, "%.2f");
  }
  return changed;
}

bool projectile_section(GuiApp& app) {
  ProjectileParams& p = app.draft.projectile;
  bool changed = false;
  int shape = int(p.shape);
  if (ImGui::Combo("shape", &shape, "sphere\0flat-faced cylinder\0cone\0")) {
    p.shape = ShapeKind(shape);
    changed = true;
  }
  changed |= slider_si("diameter (mm)", &p.diameter_m, 1e3, 1, 30, "%.1f");
  changed |= slider_si("mass (g)", &p.mass_kg, 1e3, 0.5, 50, "%.2f", true);
  changed |= slider_si("velocity (m/s)", &p.velocity_mps, 1, 10, 1000, "%.0f", true);
  ImGui::TextDisabled("impact energy %.1f J", 0.5 * p.mass_kg * p.velocity_mps * p.velocity_mps);
  changed |= slider_si("friction mu_p", &p.friction, 1, 0, 1, "%.2f");
  help_marker("Projectile-yarn Coulomb friction (Eq 20-22). The paper uses 0.27.");
  if (tree_node(app, "Strike point and obliquity")) {
    changed |= slider_si("offset x (mm)", &p.offset_x_m, 1e3, -30, 30, "%.2f");
    changed |= slider_si("offset y (mm)", &p.offset_y_m, 1e3, -30, 30, "%.2f");
    help_marker(
        "Strike point from the fabric centre. Off-centre strikes need a half or the full model (4x the nodes); "
        "0.422 mm (half a yarn spacing) puts the strike between yarns.");
    changed |= slider_si("obliquity (deg)", &p.obliquity_deg, 1, 0, 80, "%.0f");
    ImGui::BeginDisabled(p.shape == ShapeKind::sphere);
    changed |= slider_si("length (mm)", &p.length_m, 1e3, 1, 40, "%.1f");
    help_marker("Cylinder length / cone height.");
    ImGui::EndDisabled();
    ImGui::TreePop();
  }
  return changed;
}

bool friction_section(GuiApp& app) {
  bool changed = slider_si("yarn-yarn mu", &app.draft.yarn.friction, 1, 0, 1, "%.2f");
  help_marker(
      "Inter-yarn Coulomb friction (Eq 12-15). The paper studies 0 to 1; "
      "0.2 absorbs the most energy at 260 m/s.");
  for (double mu : {0.0, 0.1, 0.2, 0.4, 1.0}) {
    char label[16];
    std::snprintf(label, sizeof label, "%.1f", mu);
    if (mu != 0.0) ImGui::SameLine();
    if (ImGui::Button(label)) {
      app.draft.yarn.friction = mu;
      changed = true;
    }
  }
  return changed;
}

bool solver_section(GuiApp& app) {
  SolverParams& s = app.draft.solver;
  bool changed = false;
  int model = s.model == ContactModel::sliding ? 0 : 1;
  if (ImGui::Combo("model", &model, "sliding (paper)\0pin-jointed\0")) {
    s.model = model == 0 ? ContactModel::sliding : ContactModel::pin_jointed;
    changed = true;
  }
  changed |= slider_si("dt factor", &s.dt_factor, 1, 0.05, 1.5, "%.2f");
  help_marker(
      "alpha of Eq 4: dt = alpha L / c. Above about 1 the explicit scheme is unstable "
      "and the run will diverge (it pauses and says so).");
  changed |= ImGui::SliderInt("iterations N", &s.contact_iterations, 1, 10);
  help_marker("N passes of the yarn contact correction per step (Eq 16-17).");
  int sym = s.symmetry == SymmetryMode::automatic ? 0 : 1;
  if (ImGui::Combo("symmetry", &sym, "auto (smallest model)\0full fabric\0")) {
    s.symmetry = sym == 0 ? SymmetryMode::automatic : SymmetryMode::full;
    changed = true;
  }
  int prec = s.precision == Precision::double_precision ? 0 : 1;
  if (ImGui::Combo("precision", &prec, "double\0float\0")) {
    s.precision = prec == 0 ? Precision::double_precision : Precision::single_precision;
    changed = true;
  }
  changed |= slider_si("end time (\xC2\xB5s)", &s.end_time_s, 1e6, 5, 500, "%.0f");
  int threads = s.threads;
  if (ImGui::SliderInt("solver threads", &threads, 0, 8, threads == 0 ? "all cores" : "%d")) {
    s.threads = threads;
    app.worker->set_threads(threads);  // live: applied at the next step boundary
  }
  return changed;
}

// Checkboxes two to a row, so they fit a narrow panel.
void checkbox_grid(const char* id, std::initializer_list<std::pair<const char*, bool*>> boxes) {
  if (!ImGui::BeginTable(id, 2)) return;
  for (const auto& [label, value] : boxes) {
    ImGui::TableNextColumn();
    ImGui::Checkbox(label, value);
  }
  ImGui::EndTable();
}

// Radio buttons that wrap onto the next line when the panel is narrow.
template <class E>
void radio_row(const char* const* labels, int n, E* value) {
  const float right = ImGui::GetCursorScreenPos().x + ImGui::GetContentRegionAvail().x;
  for (int i = 0; i < n; ++i) {
    const float w = ImGui::GetFrameHeight() + ImGui::GetStyle().ItemInnerSpacing.x + ImGui::CalcTextSize(labels[i]).x;
    if (i > 0) {
      ImGui::SameLine();
      if (ImGui::GetCursorScreenPos().x + w > right) ImGui::NewLine();
    }
    if (ImGui::RadioButton(labels[i], int(*value) == i)) *value = E(i);
  }
}

void view_section(GuiApp& app) {
  render::ViewOptions& o = app.view_options;
  const char* names[] = {"Oblique", "Top", "Back", "Section"};
  const float full = ImGui::GetContentRegionAvail().x;
  const float quarter = (full - 3 * ImGui::GetStyle().ItemSpacing.x) / 4;
  for (int i = 0; i < 4; ++i) {
    if (i) ImGui::SameLine();
    if (accent_button(names[i], int(o.view) == i, ImVec2(quarter, 0))) {
      o.view = render::ViewPreset(i);
      app.camera_needs_fit = true;
    }
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s view [%d]", names[i], i + 1);
  }
  if (ImGui::Button("Fit [F]")) app.camera_needs_fit = true;
  ImGui::SameLine();
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("drag: orbit, right-drag: pan, wheel: zoom, click: pick");
  ImGui::PopTextWrapPos();
  if (!app.mode_field.empty()) {
    // Compare and demos draw their runs with the field the demo chose.
    ImGui::TextDisabled("colour: %s (set by the demo)", app.mode_field.c_str());
  } else {
    ImGui::TextUnformatted("colour");
    ImGui::SameLine();
    const char* fields[] = {"strain", "speed", "sliding", "friction"};
    radio_row(fields, 4, &o.field);
  }
  // Colour map and range: the range follows the field (strain: 0-1 of the failure strain,
  // speed: 0 to the impact velocity, sliding: 0 to the frame's maximum) unless locked.
  int map = int(o.map);
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 7);
  if (ImGui::Combo("map", &map, "turbo\0viridis\0inferno\0gray\0")) o.map = render::ColorMap(map);
  ImGui::SameLine();
  if (ImGui::Checkbox("lock range", &app.range_locked)) {
    if (app.range_locked) {
      float lo = 0, hi = 1;
      render::field_range(app.shown(), o, &lo, &hi);
      o.range_min = lo;
      o.range_max = hi;
    } else {
      o.range_min = o.range_max = 0;
    }
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Keep the colour scale fixed while the run goes on (and for pictures that compare runs)");
  if (app.range_locked) {
    float r[2] = {o.range_min, o.range_max};
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.7f);
    if (ImGui::InputFloat2("range", r, "%.3g") && r[1] > r[0]) {
      o.range_min = r[0];
      o.range_max = r[1];
    }
  }
  checkbox_grid("view_boxes", {{"whole fabric", &o.mirror},
                               {"projectile", &o.show_projectile},
                               {"clamps", &o.show_clamps},
                               {"section cut", &o.section_cut},
                               {"caption", &o.show_caption},
                               {"colour bar", &o.show_colorbar},
                               {"scale bar", &o.show_scale_bar},
                               {"axes", &o.show_axes}});
  // Quality while playing: a software GL (no GPU) spends most of a UI frame on the fabric.
  const float scales[] = {1.0f, 0.75f, 0.5f};
  const char* scale_names[] = {"full", "75 %", "50 %"};
  int current = 0;
  for (int i = 0; i < 3; ++i)
    if (std::abs(app.playing_render_scale - scales[i]) < 1e-3f) current = i;
  ImGui::TextUnformatted("resolution while playing");
  help_marker(
      "The fabric is drawn at this fraction of the view's resolution while a run plays or "
      "the mouse drags, and at full resolution once everything is still. The projectile and "
      "the caption always stay sharp. Lower it if the window feels slow without a GPU.");
  radio_row(scale_names, 3, &current);
  app.playing_render_scale = scales[current];
  ImGui::TextUnformatted("yarns");
  help_marker(
      "Ribbons: flat strips turned to the eye and shaded as the yarn's elliptic tube, several "
      "times cheaper to draw. Auto uses them unless you zoom in close, then real tubes.");
  ImGui::SameLine();
  const char* geometries[] = {"auto", "tubes", "ribbons"};
  radio_row(geometries, 3, &o.yarn_geometry);
}

void export_section(GuiApp& app) {
  char dir[512];
  std::snprintf(dir, sizeof dir, "%s", app.export_dir.c_str());
  if (ImGui::InputText("folder", dir, sizeof dir)) app.export_dir = dir;
  const float full = ImGui::GetContentRegionAvail().x;
  const float half = (full - ImGui::GetStyle().ItemSpacing.x) / 2;
  if (ImGui::Button("Screenshot", ImVec2(half, 0))) {
    app.screenshot_requested = true;
    app.screenshot_path = next_screenshot_path(app);
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("PNG of the whole window [P]");
  ImGui::SameLine();
  if (ImGui::Button("CSV + JSON", ImVec2(half, 0))) export_results(app);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("history.csv and summary.json of the run on screen");
  if (ImGui::Button("Scene TOML", ImVec2(half, 0))) export_scene(app);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("A scene file that reproduces the run on screen: ravel gui FILE");
  ImGui::SameLine();
  ImGui::BeginDisabled(app.timeline.empty() || export_running(app));
  if (ImGui::Button("VTK series", ImVec2(half, 0))) start_vtk_export(app, app.export_dir + "/vtk");
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip("Every kept frame of the run as VTU files and frame.pvd (ParaView), into <folder>/vtk");
  if (ImGui::Button("Image sequence (+ MP4)", ImVec2(full, 0))) start_image_export(app, app.export_dir + "/images");
  if (ImGui::IsItemHovered(ImGuiHoveredFlags_AllowWhenDisabled))
    ImGui::SetTooltip(
        "The 3D view of every kept frame as PNGs into <folder>/images, with this camera; and movie.mp4 where ffmpeg "
        "is installed");
  ImGui::EndDisabled();
  const int n = int(app.view.past_runs.size());
  ImGui::BeginDisabled(n == 0);
  char label[64];
  std::snprintf(label, sizeof label, "Clear %d earlier run%s from the charts [C]", n, n == 1 ? "" : "s");
  if (ImGui::Button(label, ImVec2(full, 0))) app.worker->clear_past_runs();
  ImGui::EndDisabled();
}

#ifdef RAVEL_HAVE_STUDIES_IMGUI
StabilityWindow& stability_window(GuiApp& app) {
  if (!app.stability) app.stability = std::make_unique<StabilityWindow>();
  StabilityWindow& w = *app.stability;
  // RAVEL_STABILITY_CSV=FILE opens the window on that file at start (screenshots, tests).
  if (!w.env_checked) {
    w.env_checked = true;
    if (const char* p = std::getenv("RAVEL_STABILITY_CSV")) {
      std::snprintf(w.path, sizeof w.path, "%s", p);
      w.open = true;
      try {
        w.load_text(studies::read_text_file(w.path), w.path);
      } catch (const std::exception& e) {
        w.message = e.what();
      }
    }
  }
  return w;
}

void stability_button(GuiApp& app) {
  StabilityWindow& w = stability_window(app);
  if (ImGui::Button("Stability map", ImVec2(ImGui::GetContentRegionAvail().x, 0))) w.open = !w.open;
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Where the methods fail: load stability.csv from 'ravel stability', or map dt_factor here");
}

void draw_stability_window(GuiApp& app) {
  StabilityWindow& w = stability_window(app);
  if (!w.open) return;
  if (!w.running && w.worker.joinable()) {  // a map run finished: show it
    w.worker.join();
    w.load_text(w.result_csv, "this scene (dt_factor map)");
  }
  ImGui::SetNextWindowSize(ImVec2(860, 640), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Stability map", &w.open)) {
    ImGui::End();
    return;
  }
  ImGui::InputText("stability.csv", w.path, sizeof w.path);
  ImGui::SameLine();
  if (ImGui::Button("Load")) {
    try {
      w.load_text(studies::read_text_file(w.path), w.path);
    } catch (const std::exception& e) {
      w.charts.clear();
      w.message = e.what();
    }
  }
  ImGui::BeginDisabled(w.running);
  if (ImGui::Button("Map dt_factor for this scene")) {
    studies::StabilityOptions opt;
    opt.scene_path = app.draft.source;
    try {
      // The draft as a scene file, so the map runs what the panels show.
      // A fresh folder: finished cases of an earlier draft would otherwise be resumed.
      std::filesystem::remove_all(app.export_dir + "/stability/dt_factor");
      prepare_output_dir(app.export_dir + "/stability");
      const std::string scene_file = app.export_dir + "/stability/scene.toml";
      write_file_atomic(scene_file, scene_to_toml(app.draft));
      opt.scene_path = scene_file;
      opt.out_dir = app.export_dir + "/stability";
      opt.maps = {studies::default_stability_maps(true)[0]};
      opt.jobs = 1;
      w.interrupt = false;
      w.running = true;
      w.message = "running " + std::to_string(opt.maps[0].x.values.size() * opt.maps[0].y.values.size()) +
                  " runs into " + opt.out_dir + " ...";
      w.worker = std::thread([&w, opt] {
        try {
          const auto r = studies::run_stability(opt, &w.interrupt);
          w.result_csv = studies::stability_csv(r);
          write_file_atomic(opt.out_dir + "/stability.csv", w.result_csv);
        } catch (const std::exception&) {
          w.result_csv.clear();
        }
        w.running = false;
      });
    } catch (const std::exception& e) {
      w.message = e.what();
    }
  }
  ImGui::EndDisabled();
  if (w.running) {
    ImGui::SameLine();
    if (ImGui::Button("Cancel")) w.interrupt = true;
  }
  ImGui::TextWrapped("%s", w.message.c_str());
  for (const auto& [stem, chart] : w.charts) {
    const float width = ImGui::GetContentRegionAvail().x;
    studies::draw_chart_imgui(chart, ImVec2(width, std::max(200.0f, 0.45f * width)));
  }
  ImGui::End();
}
#else
void stability_button(GuiApp&) {}
void draw_stability_window(GuiApp&) {}
#endif

}  // namespace

void check_layout(GuiApp& app, const char* panel) {
  // From the sixth frame on: a panel's scroll bar appears a frame after its content first
  // outgrows it, and the frame in between is not a layout anyone sees.
  if (!app.layout_check || ImGui::GetFrameCount() < 6) return;
  // Content wider than the panel is clipped (nothing scrolls sideways); content taller than
  // the panel must scroll. ContentSize is the extent the items reached last frame.
  const ImGuiWindow* w = ImGui::GetCurrentWindow();
  const float avail_w = w->ContentRegionRect.GetWidth(), avail_h = w->ContentRegionRect.GetHeight();
  char b[200];
  if (w->ContentSize.x > avail_w + 1.0f) {
    std::snprintf(b, sizeof b, "%s: content %.0f px wide in %.0f px", panel, w->ContentSize.x, avail_w);
    app.layout_problems.push_back(b);
  }
  if (w->ContentSize.y > avail_h + 1.0f && !w->ScrollbarY && !(w->Flags & ImGuiWindowFlags_NoScrollbar)) {
    std::snprintf(b, sizeof b, "%s: content %.0f px tall in %.0f px and no scroll bar", panel, w->ContentSize.y,
                  avail_h);
    app.layout_problems.push_back(b);
  }
  if (w->ContentSize.y > avail_h + 1.0f && (w->Flags & ImGuiWindowFlags_NoScrollbar)) {
    std::snprintf(b, sizeof b, "%s: content %.0f px tall in %.0f px, cut", panel, w->ContentSize.y, avail_h);
    app.layout_problems.push_back(b);
  }
}

bool restart_with_draft(GuiApp& app) {
  try {
    Scene s = parse_scene(scene_to_toml(app.draft), app.draft.source.empty() ? "app" : app.draft.source);
    s.source = app.draft.source;
    app.scene_error.clear();
    app.worker->restart(s);
    return true;
  } catch (const std::exception& e) {
    app.scene_error = e.what();
    return false;
  }
}

void set_draft_value(GuiApp& app, const std::string& key_value) {
  const std::string source = app.draft.source;
  app.draft = parse_scene(scene_to_toml(app.draft), "app", {key_value});
  app.draft.source = source;
}

void draw_left_panel(GuiApp& app) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, app.menu_h));
  ImGui::SetNextWindowSize(ImVec2(app.left_w, io.DisplaySize.y - app.menu_h));
  ImGui::Begin("controls", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus | kFixedPanel);
  ImGui::PushTextWrapPos(0);
  ImGui::TextColored(kAccent, "ravel");
  ImGui::SameLine();
  ImGui::TextDisabled("woven fabric, yarn by yarn");
  ImGui::PopTextWrapPos();
  ImGui::Separator();
  run_controls(app);
  ImGui::Spacing();

  // Widgets fill the panel but leave room for their label (and a help marker) on the right.
  ImGui::PushItemWidth(-ImGui::GetFontSize() * 9.0f);
  bool changed = false;
  if (header(app, "Scene", ImGuiTreeNodeFlags_DefaultOpen)) changed |= scene_section(app);
  if (header(app, "Projectile", ImGuiTreeNodeFlags_DefaultOpen)) changed |= projectile_section(app);
  if (header(app, "Inter-yarn friction", ImGuiTreeNodeFlags_DefaultOpen)) changed |= friction_section(app);
  if (header(app, "Solver")) changed |= solver_section(app);
  ImGui::PopItemWidth();
  if (!app.scene_error.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kBad, "%s", app.scene_error.c_str());
    ImGui::PopTextWrapPos();
  }
  // Sliders restart on release, not on every pixel of a drag.
  if (changed && app.auto_restart) {
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) restart_with_draft(app);
  }
  if (app.auto_restart && ImGui::IsMouseReleased(ImGuiMouseButton_Left) &&
      run_key(app.draft) != run_key(app.view.scene))
    restart_with_draft(app);
  if (header(app, "View", ImGuiTreeNodeFlags_DefaultOpen)) view_section(app);
  if (header(app, "Export and overlays", ImGuiTreeNodeFlags_DefaultOpen)) export_section(app);
  {
    const float full = ImGui::GetContentRegionAvail().x;
    const float half = (full - ImGui::GetStyle().ItemSpacing.x) / 2;
    if (ImGui::Button("Open scene...", ImVec2(half, 0))) app.show_open = true;
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("A scene file or a run's folder [Ctrl+O]");
    ImGui::SameLine();
    if (ImGui::Button("All scene keys...", ImVec2(half, 0))) app.show_keys = !app.show_keys;
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Every key of a scene file, with units, defaults and ranges");
  }
  stability_button(app);
  check_layout(app, "left panel");
  ImGui::End();
  draw_stability_window(app);
}

namespace {
double v_proj(const HistoryRow& r) {
  return r.projectile_velocity_mps;
}
double e_proj(const HistoryRow& r) {
  return r.ledger.projectile_ke_J;
}
double e_fabric(const HistoryRow& r) {
  return r.ledger.fabric_ke_J;
}
double e_strain(const HistoryRow& r) {
  return r.ledger.strain_energy_J;
}
double e_visc(const HistoryRow& r) {
  return r.ledger.viscous_J;
}
double e_fric(const HistoryRow& r) {
  return r.ledger.friction_work_J;
}
double e_pfric(const HistoryRow& r) {
  return r.ledger.projectile_friction_J;
}
double e_contact(const HistoryRow& r) {
  return r.ledger.contact_loss_J;
}
double e_released(const HistoryRow& r) {
  return r.ledger.released_J;
}
double e_clamp(const HistoryRow& r) {
  return r.ledger.clamp_friction_J;
}
}  // namespace

void draw_charts_panel(GuiApp& app) {
  const ImGuiIO& io = ImGui::GetIO();
  const float w = io.DisplaySize.x - app.left_w - app.status_w;
  ImGui::SetNextWindowPos(ImVec2(app.left_w, io.DisplaySize.y - app.bottom_h));
  ImGui::SetNextWindowSize(ImVec2(w, app.bottom_h));
  ImGui::Begin("charts", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoScrollbar | ImGuiWindowFlags_NoBringToFrontOnFocus |
                   kFixedPanel);
  const WorkerView& v = app.view;
  std::vector<ChartOverlay> overlays;
  for (const auto& r : v.past_runs) overlays.push_back({r.label, &r.history});
  // Time axis: what has been simulated (this run or an earlier one) plus room to grow,
  // in steps of 10 us, never past the end time; a long end time does not squash the start.
  double t_data = v.history.empty() ? 0 : v.history.back().t_s;
  for (const auto& r : v.past_runs)
    if (!r.history.empty()) t_data = std::max(t_data, r.history.back().t_s);
  double x_max = std::max(20e-6, std::ceil(t_data * 1.2 / 10e-6) * 10e-6);
  if (v.scene.solver.end_time_s > 0) x_max = std::min(x_max, std::max(v.scene.solver.end_time_s, t_data));

  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float gap = ImGui::GetStyle().ItemSpacing.x * 2;
  const float cw = (avail.x - gap) * 0.42f, ew = avail.x - gap - cw;

  ChartSpec vel;
  vel.id = "velocity";
  vel.title = "Projectile velocity";
  vel.y_label = "velocity along the flight path (m/s)";
  vel.x_max_s = x_max;
  vel.y_min = 0;
  vel.y_max = v.scene.projectile.velocity_mps;
  vel.rows = &v.history;
  // Earlier runs each in their own faint hue, so mu = 0.1 and mu = 0.4 can be told apart.
  static const ImU32 faint[] = {IM_COL32(120, 190, 255, 130), IM_COL32(140, 230, 140, 130),
                                IM_COL32(230, 140, 230, 130), IM_COL32(240, 230, 120, 130),
                                IM_COL32(160, 160, 255, 130), IM_COL32(200, 200, 200, 130)};
  vel.overlays = overlays;
  for (size_t i = 0; i < vel.overlays.size(); ++i) vel.overlays[i].color = faint[i % 6];
  char now_label[96];
  std::snprintf(now_label, sizeof now_label, "run %ld: mu %.2f, %.0f m/s (now)", v.run_id, v.scene.yarn.friction,
                v.scene.projectile.velocity_mps);
  vel.series = {{now_label, IM_COL32(255, 170, 60, 255), v_proj}};
  const double cursor = app.live ? -1.0 : app.shown().time_s;
  vel.cursor_s = cursor;
  double clicked = draw_chart(vel, ImVec2(cw, avail.y));

  ImGui::SameLine(0, gap);
  ChartSpec en;
  en.id = "energy";
  en.title = "Energy ledger";
  en.y_label = "energy, whole fabric (J)";
  en.x_max_s = x_max;
  en.y_min = 0;
  en.y_max = 0.5 * v.scene.projectile.mass_kg * v.scene.projectile.velocity_mps * v.scene.projectile.velocity_mps;
  en.rows = &v.history;
  en.overlays = overlays;
  en.series = {{"projectile KE", IM_COL32(255, 170, 60, 255), e_proj},
               {"fabric KE", IM_COL32(90, 180, 255, 255), e_fabric},
               {"strain energy", IM_COL32(110, 220, 120, 255), e_strain},
               {"viscous", IM_COL32(200, 130, 255, 255), e_visc},
               {"yarn friction", IM_COL32(255, 230, 80, 255), e_fric},
               {"projectile friction", IM_COL32(200, 150, 100, 255), e_pfric},
               {"contact loss", IM_COL32(170, 170, 170, 255), e_contact},
               {"released (broken)", IM_COL32(255, 110, 160, 255), e_released}};
  if (v.scene.fabric.clamp == ClampKind::slipping)  // (shown only when there is one)
    en.series.push_back({"clamp friction", IM_COL32(80, 220, 220, 255), e_clamp});
  en.cursor_s = cursor;
  const double clicked_en = draw_chart(en, ImVec2(ew, avail.y));
  if (clicked < 0) clicked = clicked_en;
  if (clicked >= 0) app.scrub_to(clicked);  // click a chart: show the fabric at that time
  ImGui::End();
}

void draw_status_panel(GuiApp& app) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - app.status_w, io.DisplaySize.y - app.bottom_h));
  ImGui::SetNextWindowSize(ImVec2(app.status_w, app.bottom_h));
  ImGui::Begin("status", nullptr,
               ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoBringToFrontOnFocus | kFixedPanel);
  const WorkerView& v = app.view;
  const Summary& s = v.summary;
  ImGui::PushTextWrapPos(0);  // long lines wrap in a narrow panel (the numbers are not cut)
  ImVec4 state_colour = kGood;
  std::string state = to_string(v.state);
  if (v.state == WorkerState::diverged) state_colour = kBad;
  if (v.state == WorkerState::paused) state_colour = kWarn;
  if (v.state == WorkerState::finished) {
    state_colour = ImVec4(0.6f, 0.75f, 1.0f, 1.0f);
    state = std::string("finished: ") + to_string(s.end_reason);
  }
  ImGui::TextDisabled("run %ld", v.run_id);
  ImGui::SameLine();
  ImGui::TextColored(state_colour, "%s", state.c_str());
  const double t_us = v.frame.time_s * 1e6, end_us = v.scene.solver.end_time_s * 1e6;
  char overlay[64];
  std::snprintf(overlay, sizeof overlay, "t = %.2f / %.0f \xC2\xB5s", t_us, end_us);
  ImGui::ProgressBar(end_us > 0 ? float(std::min(1.0, t_us / end_us)) : 0.0f, ImVec2(-1, 0), overlay);
  if (!app.live) ImGui::TextColored(kAccent, "showing t = %.2f \xC2\xB5s (kept frame)", app.shown().time_s * 1e6);
  if (v.steps_per_s > 0)
    ImGui::Text("%.0f steps/s, %.2f \xC2\xB5s/s, UI %.0f fps", v.steps_per_s, v.sim_us_per_wall_s, app.fps);
  else
    ImGui::TextDisabled("solver idle, UI %.0f fps", app.fps);
  ImGui::Text("%s model, %s", s.model.c_str(), s.contact_model.c_str());
  if (ImGui::IsItemHovered() && !s.model_reason.empty()) ImGui::SetTooltip("%s", s.model_reason.c_str());
  ImGui::Text("%d nodes, %d elements", s.node_count, s.element_count);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("the whole fabric; the solver models %d nodes and %d elements (%s)", s.modelled_node_count,
                      s.modelled_element_count, s.model.c_str());
  ImGui::Text("%d crossings, dt %.1f ns", s.crossing_count, s.dt_s * 1e9);
  ImGui::Separator();
  const double vel = v.history.empty() ? s.impact_velocity_mps : v.history.back().projectile_velocity_mps;
  ImGui::Text("projectile %.1f m/s (impact %.0f)", vel, s.impact_velocity_mps);
  if (s.perforated)
    ImGui::TextColored(kBad, "PERFORATED at %.1f \xC2\xB5s, exit %.1f m/s", s.perforation_time_s * 1e6,
                       s.residual_velocity_mps);
  else if (v.state == WorkerState::finished)
    ImGui::TextColored(kGood, "not perforated (%s)", to_string(s.end_reason));
  else
    ImGui::TextColored(kGood, "not perforated (yet)");
  ImGui::Text("absorbed %.2f J, friction %.2f J", s.energy_absorbed_J, s.friction_work_J);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(
        "yarn-yarn friction work: %.2f J up to the first break%s, %.2f J up to perforation%s, %.2f J "
        "over the run",
        s.friction_work_to_first_break_J, s.first_break_time_s >= 0 ? "" : " (none yet)",
        s.friction_work_to_perforation_J, s.perforated ? "" : " (not perforated)", s.friction_work_J);
  if (v.scene.fabric.clamp == ClampKind::slipping)
    ImGui::Text("clamps %.2f J, fed up to %.1f mm%s", s.clamp_friction_J, s.clamp_slip_max_m * 1e3,
                s.clamp_pulled_out > 0 ? ", yarns pulled out" : "");
  if (s.first_break_time_s >= 0)
    ImGui::Text("first break %.1f \xC2\xB5s, %.1f mm from impact", s.first_break_time_s * 1e6,
                s.first_break_distance_m * 1e3);
  ImGui::Text("broken yarns %d warp, %d weft", s.broken_warp_yarns, s.broken_weft_yarns);
  if (ImGui::IsItemHovered() && !(s.broken_warp_lines.empty() && s.broken_weft_lines.empty()))
    ImGui::SetTooltip("grid lines of the broken yarns, 0 through the aim point:\nwarp %s\nweft %s",
                      s.broken_warp_lines.empty() ? "none" : line_ranges(s.broken_warp_lines).c_str(),
                      s.broken_weft_lines.empty() ? "none" : line_ranges(s.broken_weft_lines).c_str());
  ImGui::Text("max strain %.2f %%, balance %.1e", s.max_strain * 100, s.energy_balance_error);
  if (!v.message.empty()) ImGui::TextColored(kBad, "%s", v.message.c_str());
  for (const auto& w : s.warnings) ImGui::TextColored(kWarn, "warning: %s", w.c_str());
  if (!app.notice.empty()) ImGui::TextColored(app.notice_is_error ? kBad : kGood, "%s", app.notice.c_str());
  ImGui::PopTextWrapPos();
  check_layout(app, "status panel");
  ImGui::End();
}

std::string next_screenshot_path(const GuiApp& app) {
  for (int i = 1;; ++i) {
    char name[96];
    std::snprintf(name, sizeof name, "/%s_screenshot_%03d.png", safe_file_name(app.view.scene.name).c_str(), i);
    const std::string p = app.export_dir + name;
    if (!std::filesystem::exists(p) || i > 999) return p;
  }
}

}  // namespace ravel::app::gui

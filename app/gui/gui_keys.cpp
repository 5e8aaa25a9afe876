// Every scene key in the app, and Open scene.
//
// The "Scene keys" window is generated from the same table `ravel keys` prints
// (scene_keys(): unit, built-in default, allowed range, meaning), so every key a scene
// file can hold is editable here, with the same checks: an edit goes through the scene
// parser as `--set key=value` would, and a refused value leaves the draft as it was with
// the checker's message (naming the key) shown in the window.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <toml++/toml.h>

#include "cli.h"
#include "gui_app.h"

namespace ravel::app::gui {

namespace {

// The draft's value of every key, as the text a scene file would hold (strings unquoted).
std::map<std::string, std::string> draft_values(const Scene& draft) {
  std::map<std::string, std::string> out;
  toml::table t;
  try {
    t = toml::parse(scene_to_toml(draft));
  } catch (const std::exception&) {
    return out;
  }
  for (const SceneKeyInfo& k : scene_keys()) {
    const toml::node_view<toml::node> n = t.at_path(k.key);
    if (!n) continue;
    if (auto s = n.value<std::string>(); s && n.is_string()) {
      out[k.key] = *s;
    } else if (n.is_boolean()) {
      out[k.key] = *n.value<bool>() ? "true" : "false";
    } else if (n.is_integer()) {
      out[k.key] = std::to_string(*n.value<std::int64_t>());
    } else if (n.is_floating_point()) {
      char b[40];
      std::snprintf(b, sizeof b, "%.10g", *n.value<double>());
      out[k.key] = b;
    }
  }
  return out;
}

// "a | b | c" -> {a, b, c}; anything else (a numeric range) -> {}.
std::vector<std::string> choices(const SceneKeyInfo& k) {
  std::vector<std::string> out;
  if (k.range.find(" | ") == std::string::npos || k.range.find_first_of("[(<>") != std::string::npos) return out;
  std::stringstream ss(k.range);
  for (std::string item; std::getline(ss, item, '|');) {
    item.erase(0, item.find_first_not_of(' '));
    item.erase(item.find_last_not_of(' ') + 1);
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

bool is_bool(const SceneKeyInfo& k) {
  return k.default_value == "true" || k.default_value == "false";
}

void apply(GuiApp& app, const SceneKeyInfo& k, const std::string& value, std::string* error) {
  try {
    set_draft_value(app, k.key + "=" + value);
    error->clear();
    app.scene_error.clear();
  } catch (const std::exception& e) {
    *error = e.what();
  }
}

}  // namespace

void draw_keys_window(GuiApp& app) {
  if (!app.show_keys) return;
  const float fs = ImGui::GetFontSize();
  ImGui::SetNextWindowSize(ImVec2(fs * 40, fs * 34), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowPos(ImVec2(app.view_x + fs, app.view_y + fs), ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Scene keys", &app.show_keys)) {
    ImGui::End();
    return;
  }
  std::string& filter = app.keys_filter;
  std::string& error = app.keys_error;
  std::map<std::string, std::string>& editing = app.keys_editing;  // text being typed, per key
  std::string& active_key = app.keys_active;                       // the field being typed in
  ImGui::TextWrapped(
      "Every key of a scene file, as `ravel keys` lists them. Edits go into the draft (Enter to apply a typed value); "
      "Restart runs it.");
  ImGui::SetNextItemWidth(fs * 16);
  ImGui::InputTextWithHint("##filter", "filter (e.g. friction)", &filter);
  if (!error.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(ImVec4(1.0f, 0.42f, 0.38f, 1.0f), "%s", error.c_str());
    ImGui::PopTextWrapPos();
  }
  const auto values = draft_values(app.draft);
  std::string section;
  if (ImGui::BeginTable("keys", 3,
                        ImGuiTableFlags_RowBg | ImGuiTableFlags_ScrollY | ImGuiTableFlags_SizingStretchProp)) {
    ImGui::TableSetupScrollFreeze(0, 1);
    ImGui::TableSetupColumn("key", ImGuiTableColumnFlags_WidthStretch, 1.2f);
    ImGui::TableSetupColumn("value", ImGuiTableColumnFlags_WidthStretch, 1.0f);
    ImGui::TableSetupColumn("unit", ImGuiTableColumnFlags_WidthFixed, fs * 3.5f);
    ImGui::TableHeadersRow();
    for (const SceneKeyInfo& k : scene_keys()) {
      if (!filter.empty() && k.key.find(filter) == std::string::npos && k.description.find(filter) == std::string::npos)
        continue;
      ImGui::PushID(k.key.c_str());
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(k.key.c_str());
      if (ImGui::IsItemHovered()) {
        ImGui::BeginTooltip();
        ImGui::PushTextWrapPos(fs * 30);
        ImGui::TextUnformatted(k.description.c_str());
        ImGui::TextDisabled("default %s%s%s", k.default_value.c_str(), k.range.empty() ? "" : ", allowed ",
                            k.range.c_str());
        ImGui::PopTextWrapPos();
        ImGui::EndTooltip();
      }
      ImGui::TableNextColumn();
      ImGui::SetNextItemWidth(-1);
      const auto it = values.find(k.key);
      const std::string current = it == values.end() ? "" : it->second;
      const auto opts = choices(k);
      if (is_bool(k)) {
        bool b = current == "true";
        if (ImGui::Checkbox("##v", &b)) apply(app, k, b ? "true" : "false", &error);
      } else if (!opts.empty()) {
        if (ImGui::BeginCombo("##v", current.c_str())) {
          for (const auto& o : opts)
            if (ImGui::Selectable(o.c_str(), o == current)) apply(app, k, o, &error);
          ImGui::EndCombo();
        }
      } else {
        // While a field is being typed in it keeps the typed text; otherwise it shows the draft.
        std::string& text = editing[k.key];
        if (active_key != k.key) text = current;
        if (ImGui::InputText("##v", &text, ImGuiInputTextFlags_EnterReturnsTrue)) apply(app, k, text, &error);
        if (ImGui::IsItemActive())
          active_key = k.key;
        else if (active_key == k.key)
          active_key.clear();
      }
      ImGui::TableNextColumn();
      ImGui::TextDisabled("%s", k.unit.c_str());
      ImGui::PopID();
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

bool open_scene(GuiApp& app, const std::string& path_in) {
  std::string path = path_in;
  while (!path.empty() && (path.back() == ' ' || path.back() == '\n')) path.pop_back();
  try {
    CommonArgs a;
    a.scene_path = path;
    Scene s = load_scene(scene_path_from(a));
    // The panels edit the opened scene only once its run has started: a refusal (too big
    // for memory, say) leaves the draft, and the run, as they were.
    Scene before = std::move(app.draft);
    app.draft = std::move(s);
    app.scene_error.clear();
    if (!restart_with_draft(app)) {
      app.open_error = app.scene_error;
      app.notice = "open: " + app.scene_error;
      app.notice_is_error = true;
      app.draft = std::move(before);
      app.scene_error.clear();
      return false;
    }
    app.open_error.clear();
    app.recent_scenes.erase(std::remove(app.recent_scenes.begin(), app.recent_scenes.end(), path),
                            app.recent_scenes.end());
    app.recent_scenes.push_front(path);
    while (app.recent_scenes.size() > 8) app.recent_scenes.pop_back();
    app.camera_needs_fit = true;
    app.notice = "opened " + path;
    app.notice_is_error = false;
    return true;
  } catch (const std::exception& e) {
    // The current run is kept; the checker's message (key, file:line, problem) is shown.
    app.open_error = e.what();
    app.notice = std::string("open: ") + e.what();
    app.notice_is_error = true;
    return false;
  }
}

void draw_open_window(GuiApp& app) {
  if (!app.show_open) return;
  const float fs = ImGui::GetFontSize();
  ImGui::SetNextWindowSize(ImVec2(fs * 34, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowPos(ImVec2(app.view_x + app.view_w * 0.5f, app.view_y + app.view_h * 0.3f), ImGuiCond_Appearing,
                          ImVec2(0.5f, 0.5f));
  if (!ImGui::Begin("Open scene", &app.show_open, ImGuiWindowFlags_NoCollapse)) {
    ImGui::End();
    return;
  }
  ImGui::TextWrapped(
      "A scene file (.toml), a run's output folder (its scene.toml) or the name of a shipped scene. "
      "You can also drop a file on the window.");
  ImGui::SetNextItemWidth(-fs * 5);
  const bool enter = ImGui::InputText("##path", &app.open_path, ImGuiInputTextFlags_EnterReturnsTrue);
  ImGui::SameLine();
  if ((ImGui::Button("Open") || enter) && !app.open_path.empty()) open_scene(app, app.open_path);
  if (!app.recent_scenes.empty()) {
    ImGui::TextDisabled("recent");
    for (const auto& r : app.recent_scenes)
      if (ImGui::Selectable(r.c_str())) {
        app.open_path = r;
        open_scene(app, r);
        break;
      }
  }
  if (!app.shipped_scenes.empty()) {
    ImGui::TextDisabled("shipped");
    for (const auto& p : app.shipped_scenes)
      if (ImGui::Selectable(std::filesystem::path(p).filename().string().c_str())) {
        app.open_path = p;
        open_scene(app, p);
        break;
      }
  }
  if (!app.open_error.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(ImVec4(1.0f, 0.42f, 0.38f, 1.0f), "%s", app.open_error.c_str());
    ImGui::TextDisabled("The run on screen was kept.");
    ImGui::PopTextWrapPos();
  }
  ImGui::End();
}

}  // namespace ravel::app::gui

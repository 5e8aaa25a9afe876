// Draw a studies::Chart into the current ImGui window (the same layout as the SVG and PNG
// files: draw_chart() through an ImDrawList painter). GUI builds only: link the target
// ravel_studies_imgui.
#pragma once

#include <imgui.h>

#include <string>
#include <vector>

#include "chart.h"

namespace ravel::studies {

// Reserve a `size` region at the cursor (ImGui::Dummy) and draw the chart into it.
// size.x / size.y <= 0 take the available width / 60 % of it.
void draw_chart_imgui(const Chart& chart, ImVec2 size = ImVec2(0, 0));

}  // namespace ravel::studies

namespace ravel::studies {

class SweepRunner;

// A sweep panel for the app: --vary lines, output folder, jobs, Start / Cancel, a progress
// bar with cases per hour, and the live charts of the cases done so far. `scene_path` and
// `overrides` are the app's current scene (a file, or "" for the default) and its edits.
void draw_sweep_panel(SweepRunner& runner, const std::string& scene_path, const std::vector<std::string>& overrides);

}  // namespace ravel::studies

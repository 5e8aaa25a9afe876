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

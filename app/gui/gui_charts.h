// Time-history charts drawn with ImGui's draw lists: axes with ticks and units, a legend,
// the current run in full colour and earlier runs as faint overlays, a hover read-out.
#pragma once

#include <imgui.h>

#include <string>
#include <vector>

#include "simulation.h"

namespace ravel::app::gui {

using RowValue = double (*)(const HistoryRow&);

struct ChartSeries {
  std::string label;
  ImU32 color = 0xffffffff;
  RowValue value = nullptr;
};

// One earlier run drawn faintly behind the current one.
struct ChartOverlay {
  std::string label;
  const std::vector<HistoryRow>* rows = nullptr;
  ImU32 color = 0;  // 0: each series in its own colour, faint; else this colour for all
};

struct ChartSpec {
  const char* id = "chart";
  std::string title;
  std::string x_label = "time (\xC2\xB5s)";  // the x axis is always time
  std::string y_label;                       // with unit, e.g. "velocity (m/s)"
  double x_max_s = 0;                        // axis end, seconds
  double y_min = 0, y_max = 1;               // axis range (grown to fit the data)
  std::vector<ChartSeries> series;
  const std::vector<HistoryRow>* rows = nullptr;  // the current run
  std::vector<ChartOverlay> overlays;
  double cursor_s = -1;  // a vertical line at this time (the time on show when scrubbing); < 0: none
};

// Draw the chart into a region of `size` at the cursor. Returns the time (s) under a mouse
// click in the plot (the app scrubs there), or -1.
double draw_chart(const ChartSpec& spec, ImVec2 size);

// A "nice" tick step (1, 2 or 5 x 10^n) giving about `target` ticks over `range`.
double nice_step(double range, int target);

}  // namespace ravel::app::gui

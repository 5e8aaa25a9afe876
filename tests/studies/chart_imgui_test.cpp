// The app's charts (studies/chart_imgui.cpp) drawn into an ImGui draw list with no window
// system: ImGui builds its draw lists on the CPU, so the glyphs a chart emits can be counted.
#include <gtest/gtest.h>
#include <imgui.h>

#include "chart_imgui.h"

namespace ravel::studies {
namespace {

Chart energy_chart() {
  Chart c;
  c.title = "energy absorbed vs yarn.friction";
  c.x.label = "yarn.friction";
  c.y.label = "energy absorbed";
  c.y.unit = "J";
  Series s;
  s.name = "energy";
  s.x = {0.1, 0.2};
  s.y = {50.4, 75.9};
  c.series.push_back(s);
  return c;
}

// Vertices the chart adds to a window's draw list, with the window's left edge at `x`.
int vertices_at(const Chart& chart, float x, ImVec2 size) {
  ImGuiIO& io = ImGui::GetIO();
  io.DisplaySize = ImVec2(1600, 900);
  io.DeltaTime = 1.0f / 60;
  ImGui::NewFrame();
  ImGui::SetNextWindowPos(ImVec2(x, 40));
  ImGui::SetNextWindowSize(ImVec2(size.x + 20, size.y + 20));
  ImGui::Begin("chart", nullptr, ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoSavedSettings);
  ImDrawList* dl = ImGui::GetWindowDrawList();
  const int before = dl->VtxBuffer.Size;
  draw_chart_imgui(chart, size);
  const int added = dl->VtxBuffer.Size - before;
  ImGui::End();
  ImGui::EndFrame();
  return added;
}

class ChartImgui : public ::testing::Test {
 protected:
  void SetUp() override {
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini left in the working folder
    unsigned char* pixels;
    int w, h;
    ImGui::GetIO().Fonts->GetTexDataAsAlpha8(&pixels, &w, &h);  // builds the font atlas
  }
  void TearDown() override { ImGui::DestroyContext(); }
};

// The rotated y title is laid out as a line and then turned; ImGui drops the glyphs of a
// line outside the clip rectangle, so a title centred on an axis near the window's left edge
// lost its first letters ("y absorbed (J)" in the app's Sweep window). At the screen's left
// edge the chart must emit every glyph it emits in the middle of the screen.
TEST_F(ChartImgui, VerticalTitleKeepsEveryGlyphAtTheWindowsLeftEdge) {
  const Chart chart = energy_chart();
  const ImVec2 size(760, 170);
  const int middle = vertices_at(chart, 600, size);
  const int edge = vertices_at(chart, 0, size);
  EXPECT_GT(middle, 0);
  EXPECT_EQ(edge, middle);
  // And the title's glyphs are all there: without it the chart has 4 vertices per glyph less.
  Chart untitled = chart;
  untitled.y.label.clear();
  untitled.y.unit.clear();
  int glyphs = 0;
  for (char ch : chart.y.title()) glyphs += ch != ' ';
  EXPECT_EQ(middle - vertices_at(untitled, 600, size), 4 * glyphs);
}

}  // namespace
}  // namespace ravel::studies

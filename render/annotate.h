// Annotator: 2D annotations drawn on top of a rendered view, for teaching pictures.
//
// World-space polylines (e.g. the theoretical wave fronts over the fabric) are projected
// with the view's Camera and drawn as anti-aliased-looking thick lines in viewport pixels;
// text blocks (captions, labels) are placed in viewport pixels. No depth test: the
// annotations always sit on top of the fabric, the projectile and the renderer's own
// caption. Like Renderer, construct it with a current context whose GL entry points are
// loaded, and use and destroy it with that context current; one per context.
//
// The geometry (where every line lands in pixels) is computed by annotation_geometry(),
// which needs no GL, so tests can compare a drawn line with the formula behind it.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace ravel::render {

struct WorldPolyline {
  std::vector<Vec3> points;  // world coordinates (m)
  bool closed = false;       // join the last point to the first
  Vec3 color{1.0f, 0.85f, 0.2f};
  float width_px = 2.5f;  // line width in viewport pixels (before ui scale)
  bool dashed = false;
  std::string label;       // drawn beside `label_at` (empty: none)
  Vec3 label_at{0, 0, 0};  // world point the label sits next to
};

struct TextBlock {
  // Top-left corner in viewport pixels, origin top-left. Negative y: measured up from the
  // bottom edge to the block's bottom; negative x: from the right edge to its right side.
  float x = 0, y = 0;
  std::vector<std::string> lines;
  std::vector<Vec3> colors;  // per line; missing entries are white
  float scale = 0;           // font pixel size; 0 = from the viewport height
  bool panel = true;         // dark translucent panel behind the text
  float min_width_px = 0;    // panel at least this wide (a full-width banner)
};

// A line segment in viewport pixels (origin top-left, y down).
struct PixelSegment {
  float x0, y0, x1, y1;
};
// The pixel segments a polyline becomes in a viewport of w x h pixels under `camera`
// (segments with an end behind the eye are dropped).
std::vector<PixelSegment> annotation_geometry(const WorldPolyline& line, const Camera& camera, int w, int h);

class Annotator {
 public:
  Annotator();
  ~Annotator();
  Annotator(const Annotator&) = delete;
  Annotator& operator=(const Annotator&) = delete;

  // Draw into the viewport (x, y, w, h) of the bound framebuffer, GL window coordinates
  // (y up), on top of what is there. Nothing is cleared.
  void draw(const Camera& camera, const std::vector<WorldPolyline>& lines, const std::vector<TextBlock>& texts, int x,
            int y, int w, int h);

  // Width in pixels of a text line at a font scale (as drawn).
  static float text_width(const std::string& s, float scale);
  // The text scale used for a viewport of height h when TextBlock::scale is 0.
  static float default_scale(int h);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ravel::render

// Internal: 2D overlay geometry (caption panel, colour bar, text) in viewport pixels,
// origin at the top-left, y down. Text comes from stb_easy_font (libstb-dev).
#pragma once

#include <string>
#include <vector>

namespace ravel::render {

struct OverlayVertex {
  float x, y;
  float r, g, b, a;
};

struct Rgba {
  float r, g, b, a;
};

class OverlayBatch {
 public:
  void clear() { vertices_.clear(); }
  void rect(float x0, float y0, float x1, float y1, Rgba c) { quad(x0, y0, x1, y1, c, c, c, c); }
  // Corners: top-left, top-right, bottom-right, bottom-left.
  void quad(float x0, float y0, float x1, float y1, Rgba tl, Rgba tr, Rgba br, Rgba bl);
  // A straight line of the given width (pixels) from (x0, y0) to (x1, y1).
  void line(float x0, float y0, float x1, float y1, float width, Rgba c);
  // Text with its top-left at (x, y); each font pixel becomes scale x scale pixels.
  void text(float x, float y, const std::string& s, float scale, Rgba c);
  // Text with a dark drop shadow, for reading on any background.
  void text_shadowed(float x, float y, const std::string& s, float scale, Rgba c);
  static float text_width(const std::string& s, float scale);
  static float text_height(float scale) { return 7.0f * scale; }  // cap height
  const std::vector<OverlayVertex>& vertices() const { return vertices_; }

 private:
  std::vector<OverlayVertex> vertices_;  // triangles
};

}  // namespace ravel::render

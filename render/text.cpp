#include <cmath>
#include <vector>

#include "render/overlay.h"

// stb_easy_font is a header of static functions; its implementation lives in this file.
#include <stb/stb_easy_font.h>

namespace ravel::render {

void OverlayBatch::quad(float x0, float y0, float x1, float y1, Rgba tl, Rgba tr, Rgba br, Rgba bl) {
  const OverlayVertex a{x0, y0, tl.r, tl.g, tl.b, tl.a}, b{x1, y0, tr.r, tr.g, tr.b, tr.a},
      c{x1, y1, br.r, br.g, br.b, br.a}, d{x0, y1, bl.r, bl.g, bl.b, bl.a};
  vertices_.insert(vertices_.end(), {a, b, c, a, c, d});
}

void OverlayBatch::line(float x0, float y0, float x1, float y1, float width, Rgba c) {
  const float dx = x1 - x0, dy = y1 - y0, len = std::sqrt(dx * dx + dy * dy);
  if (!(len > 0)) return;
  const float nx = -dy / len * 0.5f * width, ny = dx / len * 0.5f * width;
  const OverlayVertex a{x0 + nx, y0 + ny, c.r, c.g, c.b, c.a}, b{x1 + nx, y1 + ny, c.r, c.g, c.b, c.a},
      d{x1 - nx, y1 - ny, c.r, c.g, c.b, c.a}, e{x0 - nx, y0 - ny, c.r, c.g, c.b, c.a};
  vertices_.insert(vertices_.end(), {a, b, d, a, d, e});
}

void OverlayBatch::text(float x, float y, const std::string& s, float scale, Rgba c) {
  if (s.empty()) return;
  // stb_easy_font writes 4 vertices of 16 bytes per quad; about 270 bytes per character.
  std::vector<char> buffer(s.size() * 400 + 1024);
  std::vector<char> str(s.begin(), s.end());
  str.push_back('\0');
  unsigned char white[4] = {255, 255, 255, 255};
  const int quads = stb_easy_font_print(0, 0, str.data(), white, buffer.data(), static_cast<int>(buffer.size()));
  struct V {
    float x, y, z;
    unsigned char rgba[4];
  };
  const V* v = reinterpret_cast<const V*>(buffer.data());
  // Snap to whole pixels so the glyph segments stay crisp.
  x = std::round(x);
  y = std::round(y);
  for (int q = 0; q < quads; ++q) {
    const V* p = v + 4 * q;
    rect(x + p[0].x * scale, y + p[0].y * scale, x + p[2].x * scale, y + p[2].y * scale, c);
  }
}

void OverlayBatch::text_shadowed(float x, float y, const std::string& s, float scale, Rgba c) {
  const float o = std::max(1.0f, std::round(scale * 0.5f));
  text(x + o, y + o, s, scale, {0.0f, 0.0f, 0.0f, 0.75f * c.a});
  text(x, y, s, scale, c);
}

float OverlayBatch::text_width(const std::string& s, float scale) {
  std::vector<char> str(s.begin(), s.end());
  str.push_back('\0');
  return stb_easy_font_width(str.data()) * scale;
}

}  // namespace ravel::render

// RenderTarget: an off-window colour + depth framebuffer the renderer draws into, shown by
// copying it into the window (blit) and read back for images.
//
// One helper for every place that draws the fabric somewhere other than the window
// itself: the app's cached 3D view, the split views of compare mode and the app's image
// sequences. It needs a current GL context whose entry points are loaded (load_gl), and
// must be released with that context current. No GL header here.
#pragma once

#include <cstdint>
#include <vector>

namespace ravel::render {

class RenderTarget {
 public:
  RenderTarget() = default;
  ~RenderTarget();
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  // (Re)allocate at w x h if the size changed; returns true when it did (the contents are
  // then undefined).
  bool resize(int w, int h);
  void release();
  bool valid() const { return fbo_ != 0; }
  int width() const { return w_; }
  int height() const { return h_; }

  void bind() const;          // draw into it (viewport untouched)
  static void bind_window();  // back to the window's framebuffer
  // Copy into the window's back buffer with the lower-left corner at (x, y), 1:1.
  void blit_to_window(int x, int y) const;
  // The colour as RGB rows, top row first.
  std::vector<std::uint8_t> read_rgb() const;

 private:
  unsigned fbo_ = 0, color_ = 0, depth_ = 0;
  int w_ = 0, h_ = 0;
};

}  // namespace ravel::render

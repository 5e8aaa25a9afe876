// Picking: which yarn element or crossing lies under a point of the 3D view.
//
// The view shows the modelled part of the fabric and its mirrored copies (the same copy
// order as the renderer and the VTU files: copy 0 is the modelled part, then the copy
// mirrored across x = 0, then across y = 0). A pick names the modelled element (or
// crossing) and the copy it was seen in, so its strain, stress and history are the
// modelled item's, and the highlight can be drawn on the copy the user clicked.
//
// Screen-space and exact: every unbroken element of every copy is projected with the
// view's camera and the one whose segment passes nearest the point (within `max_px`)
// wins; between segments equally near, the one nearer the eye. About 3 ms for the
// default scene's 40,000 whole-fabric elements on one core, once per click. Elements cut
// away by the section view are not pickable.
#pragma once

#include <array>

#include "core/frame.h"
#include "render/renderer.h"

namespace ravel::render {

struct Pick {
  int element = -1;   // modelled element index (-1: nothing)
  int crossing = -1;  // modelled crossing index (-1: nothing)
  int copy = 0;       // which mirrored copy (0 = the modelled part)
  float distance_px = 0;
  std::array<float, 3> mirror{1, 1, 1};  // the copy's sign flips (x, y, z)
};

// The mirrored copies a view shows, in copy order: {1,1,1}, then {-1,1,1} (mirror_x),
// then the y mirrors of those.
std::vector<std::array<float, 3>> view_copies(const Frame& frame, const ViewOptions& options);

// The element under pixel (x_px, y_px) of a w x h view (origin top-left), or none.
Pick pick_element(const Frame& frame, const Camera& camera, const ViewOptions& options, int w, int h, float x_px,
                  float y_px, float max_px = 8.0f);
// The crossing nearest the pixel (its two tracked nodes' midpoint), within max_px.
Pick pick_crossing(const Frame& frame, const Camera& camera, const ViewOptions& options, int w, int h, float x_px,
                   float y_px, float max_px = 10.0f);

}  // namespace ravel::render

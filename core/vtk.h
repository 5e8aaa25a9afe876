// VTK output of Frames for ParaView: one UnstructuredGrid (.vtu, appended raw binary)
// per frame plus a .pvd collection that indexes them by time.
//
// Written by hand (no VTK dependency). Yarn elements are VTK_LINE cells. Point data:
// velocity (m/s), slip_rate (m/s). Cell data: strain, strain_ratio (strain / failure
// strain), stress (Pa), broken (0/1), yarn_id, family (0 warp, 1 weft), copy (which
// mirrored copy of the modelled part, 0 = the modelled part). Every file is written to a
// temporary name in the same folder and renamed, so a reader never sees half a file.
#pragma once

#include <string>
#include <vector>

#include "frame.h"

namespace ravel {

// Write `frame` as a .vtu. With `mirror`, the modelled quarter / half is mirrored (as
// the frame's mirror_x / mirror_y say) so the file holds the whole fabric.
bool write_vtu(const Frame& frame, const std::string& path, bool mirror = true, std::string* error = nullptr);

// Whole-fabric yarn id of element `element` of the frame seen in the copy mirrored by
// (sign_x, sign_y) (each +1 or -1): warp I -> I + hx, weft J -> 2 hx + 1 + J + hy, with the
// grid indices of a mirrored copy negated, so ids are unique across the copies (the VTU
// files' yarn_id, the app's picked element). -1 for an element the frame does not have.
// `half` (from yarn_half_counts) saves scanning the yarns at every call.
struct YarnHalfCounts {
  int hx = 0, hy = 0;  // largest |grid index| of the warp / weft yarns
};
YarnHalfCounts yarn_half_counts(const Frame& frame);
int whole_fabric_yarn_id(const Frame& frame, int element, float sign_x, float sign_y, const YarnHalfCounts& half);
inline int whole_fabric_yarn_id(const Frame& frame, int element, float sign_x, float sign_y) {
  return whole_fabric_yarn_id(frame, element, sign_x, sign_y, yarn_half_counts(frame));
}

struct PvdEntry {
  double time_s = 0;
  std::string file;  // relative to the .pvd's folder
};
bool write_pvd(const std::string& path, const std::vector<PvdEntry>& entries, std::string* error = nullptr);

// A time series in a folder: <dir>/<base>_00000.vtu, ... and <dir>/<base>.pvd, the .pvd
// rewritten after every frame so the series is readable while a run is going.
class VtkSeries {
 public:
  explicit VtkSeries(std::string dir, std::string base = "frame", bool mirror = true);
  bool add(const Frame& frame, std::string* error = nullptr);
  std::string pvd_path() const;
  int count() const { return static_cast<int>(entries_.size()); }

 private:
  std::string dir_, base_;
  bool mirror_;
  std::vector<PvdEntry> entries_;
};

}  // namespace ravel

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

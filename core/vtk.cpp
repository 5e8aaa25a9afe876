#include "vtk.h"

#include "results.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

namespace ravel {

namespace {

// The appended-data block: each array is a UInt64 byte count followed by its bytes.
class Appended {
 public:
  template <typename T>
  std::uint64_t add(const std::vector<T>& v) {
    const std::uint64_t offset = data_.size();
    const std::uint64_t n = v.size() * sizeof(T);
    data_.append(reinterpret_cast<const char*>(&n), sizeof n);
    data_.append(reinterpret_cast<const char*>(v.data()), n);
    return offset;
  }
  const std::string& bytes() const { return data_; }

 private:
  std::string data_;
};

template <typename T>
const char* vtk_type();
template <>
const char* vtk_type<float>() {
  return "Float32";
}
template <>
const char* vtk_type<std::uint8_t>() {
  return "UInt8";
}
template <>
const char* vtk_type<std::int32_t>() {
  return "Int32";
}
template <>
const char* vtk_type<std::int64_t>() {
  return "Int64";
}

template <typename T>
void array(std::ostringstream& xml, Appended& app, const char* name, const std::vector<T>& v, int components = 1) {
  xml << "        <DataArray type=\"" << vtk_type<T>() << "\"";
  if (name) xml << " Name=\"" << name << "\"";
  if (components > 1) xml << " NumberOfComponents=\"" << components << "\"";
  xml << " format=\"appended\" offset=\"" << app.add(v) << "\"/>\n";
}

}  // namespace

YarnHalfCounts yarn_half_counts(const Frame& f) {
  YarnHalfCounts h;
  for (std::size_t y = 0; y < f.yarn_grid.size() && y < f.yarn_family.size(); ++y) {
    int& m = f.yarn_family[y] == 0 ? h.hx : h.hy;
    m = std::max(m, std::abs(f.yarn_grid[y]));
  }
  return h;
}

int whole_fabric_yarn_id(const Frame& f, int element, float sign_x, float sign_y, const YarnHalfCounts& half) {
  if (element < 0 || std::size_t(element) >= f.elem_yarn.size()) return -1;
  const int id = int(f.elem_yarn[std::size_t(element)]);
  if (f.yarn_grid.empty() || f.yarn_grid.size() != f.yarn_family.size() || std::size_t(id) >= f.yarn_grid.size())
    return id;
  const bool warp = f.yarn_family[std::size_t(id)] == 0;
  const int sign = (warp ? sign_x : sign_y) < 0 ? -1 : 1;
  const int g = f.yarn_grid[std::size_t(id)];
  return warp ? sign * g + half.hx : (2 * half.hx + 1) + sign * g + half.hy;
}

bool write_vtu(const Frame& f, const std::string& path, bool mirror, std::string* error) {
  std::vector<std::array<float, 2>> copies = {{1, 1}};
  if (mirror && f.mirror_x) copies.push_back({-1, 1});
  if (mirror && f.mirror_y) {
    const std::size_t n = copies.size();
    for (std::size_t i = 0; i < n; ++i) copies.push_back({copies[i][0], -1});
  }
  const std::size_t np = f.node_pos.size(), ne = std::min(f.elem_a.size(), f.elem_b.size());
  const std::size_t nc = copies.size();

  // A copy mirrored across a plane repeats what lies on that plane: those points and cells
  // are marked `duplicate` = 1, so a sum over the cells or points with duplicate = 0 counts
  // the whole fabric once.
  constexpr float kOnPlane = 1e-7f;  // m: nodes on a symmetry plane stay on it
  std::vector<float> points, velocity, slip, friction;
  std::vector<std::uint8_t> point_dup;
  points.reserve(np * nc * 3);
  velocity.reserve(np * nc * 3);
  for (const auto& m : copies)
    for (std::size_t i = 0; i < np; ++i) {
      const auto& p = f.node_pos[i];
      points.insert(points.end(), {p[0] * m[0], p[1] * m[1], p[2]});
      const auto v = i < f.node_vel.size() ? f.node_vel[i] : std::array<float, 3>{0, 0, 0};
      velocity.insert(velocity.end(), {v[0] * m[0], v[1] * m[1], v[2]});
      slip.push_back(i < f.node_slip_rate.size() ? f.node_slip_rate[i] : 0.0f);
      friction.push_back(i < f.node_friction_j_per_g.size() ? f.node_friction_j_per_g[i] : 0.0f);
      point_dup.push_back((m[0] < 0 && std::abs(p[0]) < kOnPlane) || (m[1] < 0 && std::abs(p[1]) < kOnPlane));
    }
  const bool have_grid = !f.yarn_grid.empty() && f.yarn_grid.size() == f.yarn_family.size();
  const YarnHalfCounts half = yarn_half_counts(f);

  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types, broken, family, copy, cell_dup;
  std::vector<float> strain, ratio, stress;
  std::vector<std::int32_t> yarn;
  const float inv_fail = f.failure_strain > 0 ? 1.0f / f.failure_strain : 0.0f;
  for (std::size_t c = 0; c < nc; ++c)
    for (std::size_t e = 0; e < ne; ++e) {
      if (f.elem_a[e] >= np || f.elem_b[e] >= np) {
        if (error) *error = "write_vtu: element " + std::to_string(e) + " names a missing node";
        return false;
      }
      connectivity.push_back(static_cast<std::int64_t>(c * np + f.elem_a[e]));
      connectivity.push_back(static_cast<std::int64_t>(c * np + f.elem_b[e]));
      offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
      types.push_back(3);  // VTK_LINE
      const float s = e < f.elem_strain.size() ? f.elem_strain[e] : 0.0f;
      strain.push_back(s);
      ratio.push_back(s * inv_fail);
      stress.push_back(e < f.elem_stress_pa.size() ? f.elem_stress_pa[e] : 0.0f);
      broken.push_back(e < f.elem_broken.size() ? f.elem_broken[e] : 0);
      family.push_back(e < f.elem_family.size() ? f.elem_family[e] : 0);
      const std::int32_t own = e < f.elem_yarn.size() ? static_cast<std::int32_t>(f.elem_yarn[e]) : -1;
      bool dup = false;
      if (have_grid && own >= 0 && std::size_t(own) < f.yarn_grid.size()) {
        const float sign = f.yarn_family[own] == 0 ? copies[c][0] : copies[c][1];
        dup = sign < 0 && f.yarn_grid[own] == 0;
      }
      yarn.push_back(whole_fabric_yarn_id(f, int(e), copies[c][0], copies[c][1], half));
      copy.push_back(static_cast<std::uint8_t>(c));
      cell_dup.push_back(dup);
    }

  Appended app;
  std::ostringstream xml;
  // The projectile as field data (a ParaView state can place a sphere / cylinder from it).
  auto field = [&](const char* name, const char* type, int n, const std::string& values) {
    xml << "      <DataArray type=\"" << type << "\" Name=\"" << name << "\" NumberOfTuples=\"1\"";
    if (n > 1) xml << " NumberOfComponents=\"" << n << "\"";
    xml << " format=\"ascii\">" << values << "</DataArray>\n";
  };
  auto vec = [](const std::array<float, 3>& v) {
    char b[96];
    std::snprintf(b, sizeof b, "%.9g %.9g %.9g", v[0], v[1], v[2]);
    return std::string(b);
  };
  auto one = [](double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.9g", v);
    return std::string(b);
  };
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <FieldData>\n";
  field("TimeValue", "Float64", 1, one(f.time_s));
  field("projectile_position_m", "Float64", 3, vec(f.projectile_pos));
  field("projectile_axis", "Float64", 3, vec(f.projectile_axis));
  field("projectile_radius_m", "Float64", 1, one(f.projectile_radius_m));
  field("projectile_length_m", "Float64", 1, one(f.projectile_length_m));
  field("projectile_shape", "Int32", 1, std::to_string(f.projectile_shape) + "");
  xml << "    </FieldData>\n"
      << "    <Piece NumberOfPoints=\"" << np * nc << "\" NumberOfCells=\"" << ne * nc << "\">\n"
      << "      <PointData Vectors=\"velocity\" Scalars=\"slip_rate\">\n";
  array(xml, app, "velocity", velocity, 3);
  array(xml, app, "slip_rate", slip);
  array(xml, app, "friction_heat_J_per_g", friction);
  array(xml, app, "duplicate", point_dup);
  xml << "      </PointData>\n      <CellData Scalars=\"strain_ratio\">\n";
  array(xml, app, "strain", strain);
  array(xml, app, "strain_ratio", ratio);
  array(xml, app, "stress", stress);
  array(xml, app, "broken", broken);
  array(xml, app, "yarn_id", yarn);
  array(xml, app, "family", family);
  array(xml, app, "copy", copy);
  array(xml, app, "duplicate", cell_dup);
  xml << "      </CellData>\n      <Points>\n";
  array(xml, app, "Points", points, 3);
  xml << "      </Points>\n      <Cells>\n";
  array(xml, app, "connectivity", connectivity);
  array(xml, app, "offsets", offsets);
  array(xml, app, "types", types);
  xml << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n"
      << "  <AppendedData encoding=\"raw\">\n   _";
  std::string bytes = xml.str();
  bytes += app.bytes();
  bytes += "\n  </AppendedData>\n</VTKFile>\n";
  return write_file_atomic(path, bytes, error);
}

bool write_pvd(const std::string& path, const std::vector<PvdEntry>& entries, std::string* error) {
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      << "  <Collection>\n";
  char t[64];
  for (const PvdEntry& e : entries) {
    std::snprintf(t, sizeof t, "%.9g", e.time_s);
    xml << "    <DataSet timestep=\"" << t << "\" part=\"0\" file=\"" << e.file << "\"/>\n";
  }
  xml << "  </Collection>\n</VTKFile>\n";
  return write_file_atomic(path, xml.str(), error);
}

VtkSeries::VtkSeries(std::string dir, std::string base, bool mirror)
    : dir_(std::move(dir)), base_(std::move(base)), mirror_(mirror) {}

std::string VtkSeries::pvd_path() const {
  return dir_ + "/" + base_ + ".pvd";
}

bool VtkSeries::add(const Frame& frame, std::string* error) {
  char name[64];
  std::snprintf(name, sizeof name, "_%05d.vtu", count());
  const std::string file = base_ + name;
  if (!write_vtu(frame, dir_ + "/" + file, mirror_, error)) return false;
  entries_.push_back({frame.time_s, file});
  return write_pvd(pvd_path(), entries_, error);
}

}  // namespace ravel

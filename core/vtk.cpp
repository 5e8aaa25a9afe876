#include "vtk.h"

#include "results.h"

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

bool write_vtu(const Frame& f, const std::string& path, bool mirror, std::string* error) {
  std::vector<std::array<float, 2>> copies = {{1, 1}};
  if (mirror && f.mirror_x) copies.push_back({-1, 1});
  if (mirror && f.mirror_y) {
    const std::size_t n = copies.size();
    for (std::size_t i = 0; i < n; ++i) copies.push_back({copies[i][0], -1});
  }
  const std::size_t np = f.node_pos.size(), ne = std::min(f.elem_a.size(), f.elem_b.size());
  const std::size_t nc = copies.size();

  std::vector<float> points, velocity, slip;
  points.reserve(np * nc * 3);
  velocity.reserve(np * nc * 3);
  for (const auto& m : copies)
    for (std::size_t i = 0; i < np; ++i) {
      const auto& p = f.node_pos[i];
      points.insert(points.end(), {p[0] * m[0], p[1] * m[1], p[2]});
      const auto v = i < f.node_vel.size() ? f.node_vel[i] : std::array<float, 3>{0, 0, 0};
      velocity.insert(velocity.end(), {v[0] * m[0], v[1] * m[1], v[2]});
      slip.push_back(i < f.node_slip_rate.size() ? f.node_slip_rate[i] : 0.0f);
    }

  std::vector<std::int64_t> connectivity, offsets;
  std::vector<std::uint8_t> types, broken, family, copy;
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
      yarn.push_back(e < f.elem_yarn.size() ? static_cast<std::int32_t>(f.elem_yarn[e]) : -1);
      copy.push_back(static_cast<std::uint8_t>(c));
    }

  Appended app;
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << np * nc << "\" NumberOfCells=\"" << ne * nc << "\">\n"
      << "      <PointData Vectors=\"velocity\" Scalars=\"slip_rate\">\n";
  array(xml, app, "velocity", velocity, 3);
  array(xml, app, "slip_rate", slip);
  xml << "      </PointData>\n      <CellData Scalars=\"strain_ratio\">\n";
  array(xml, app, "strain", strain);
  array(xml, app, "strain_ratio", ratio);
  array(xml, app, "stress", stress);
  array(xml, app, "broken", broken);
  array(xml, app, "yarn_id", yarn);
  array(xml, app, "family", family);
  array(xml, app, "copy", copy);
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

// Scene reading: one table of keys (name, unit, type, range, where it lives in Scene)
// drives parsing, `--set` overrides, validation messages, to_toml() and `ravel keys`.
#include "scene.h"

#include "model.h"

#include <toml++/toml.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#ifndef RAVEL_ASSETS_DIR
#define RAVEL_ASSETS_DIR "assets"
#endif

namespace ravel {

SceneError::SceneError(std::string key, std::string where, std::string problem)
    : std::runtime_error((where.empty() ? std::string() : where + ": ") + (key.empty() ? std::string() : key + ": ") +
                         problem),
      key_(std::move(key)),
      where_(std::move(where)),
      problem_(std::move(problem)) {}

std::string ClampedEdges::to_string() const {
  if (left && right && bottom && top) return "all";
  if (!any()) return "none";
  std::string s;
  auto add = [&](bool on, const char* name) {
    if (!on) return;
    if (!s.empty()) s += ",";
    s += name;
  };
  add(left, "left");
  add(right, "right");
  add(bottom, "bottom");
  add(top, "top");
  return s;
}

const char* to_string(ContactModel m) {
  return m == ContactModel::sliding ? "sliding" : "pin_jointed";
}
const char* to_string(Material m) {
  return m == Material::zener ? "zener" : "elastic";
}
const char* to_string(Weave w) {
  return w == Weave::plain ? "plain" : "single_yarn";
}
const char* to_string(CrossingCompression c) {
  return c == CrossingCompression::rigid ? "rigid" : "hyperbolic";
}
const char* to_string(ClampKind c) {
  return c == ClampKind::rigid ? "rigid" : "slipping";
}
const char* to_string(ShapeKind s) {
  switch (s) {
    case ShapeKind::sphere:
      return "sphere";
    case ShapeKind::cylinder:
      return "cylinder";
    case ShapeKind::cone:
      return "cone";
  }
  return "?";
}

namespace {

enum class Type { number, integer, boolean, text };

// One scene key. `scale` converts the file's unit to SI (mm -> m is 1e-3).
struct KeyDef {
  std::string key, unit, description;
  Type type;
  double scale = 1.0;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  std::vector<std::string> choices;                // for text enums
  std::function<void(Scene&, double)> set_number;  // SI value
  std::function<double(const Scene&)> get_number;  // SI value
  std::function<void(Scene&, const std::string&)> set_text;
  std::function<std::string(const Scene&)> get_text;
  // Number keys that also take the word "auto" (solver.end_time_us).
  std::function<void(Scene&)> set_auto = nullptr;
  std::function<bool(const Scene&)> is_auto = nullptr;
};

#define NUM(KEY, UNIT, DESC, SCALE, MIN, MINEX, MAX, FIELD)                              \
  {                                                                                      \
    KeyDef d{KEY, UNIT, DESC, Type::number, SCALE, MIN, MAX, MINEX, {}, {}, {}, {}, {}}; \
    d.set_number = [](Scene& s, double v) { s.FIELD = v; };                              \
    d.get_number = [](const Scene& s) { return double(s.FIELD); };                       \
    defs.push_back(std::move(d));                                                        \
  }
#define INT(KEY, UNIT, DESC, MIN, MAX, FIELD)                                           \
  {                                                                                     \
    KeyDef d{KEY, UNIT, DESC, Type::integer, 1.0, MIN, MAX, false, {}, {}, {}, {}, {}}; \
    d.set_number = [](Scene& s, double v) { s.FIELD = int(v); };                        \
    d.get_number = [](const Scene& s) { return double(s.FIELD); };                      \
    defs.push_back(std::move(d));                                                       \
  }
#define BOOL(KEY, DESC, FIELD)                                                    \
  {                                                                               \
    KeyDef d{KEY, "", DESC, Type::boolean, 1.0, 0, 1, false, {}, {}, {}, {}, {}}; \
    d.set_number = [](Scene& s, double v) { s.FIELD = v != 0; };                  \
    d.get_number = [](const Scene& s) { return s.FIELD ? 1.0 : 0.0; };            \
    defs.push_back(std::move(d));                                                 \
  }

constexpr double inf = std::numeric_limits<double>::infinity();

// A key whose value is one of a fixed list of words (an enum of the scene).
void text_key(std::vector<KeyDef>& defs, const char* key, const char* desc, std::vector<std::string> choices,
              std::function<void(Scene&, const std::string&)> set, std::function<std::string(const Scene&)> get) {
  KeyDef d{key, "", desc, Type::text, 1.0, 0, 0, false, {}, {}, {}, {}, {}};
  d.choices = std::move(choices);
  d.set_text = std::move(set);
  d.get_text = std::move(get);
  defs.push_back(std::move(d));
}
// Node mass vs rho A L: warn beyond 25 %, refuse beyond a factor 3.
constexpr double kNodeMassWarnFraction = 0.25;
constexpr double kNodeMassErrorFactor = 3.0;
// Memory per modelled node of a run (solver state, scratch, history): 1045 bytes measured
// on the default scene at 162,450 nodes (peak resident size, 480 x 480 mm, less the
// 120 x 120 mm run's), with a margin for the app's frame copies.
constexpr double kBytesPerNode = 1200;
// Memory the system has available (MemAvailable of /proc/meminfo); 0 when unknown.
double available_memory_bytes() {
  std::ifstream in("/proc/meminfo");
  std::string name;
  double kb = 0;
  std::string unit;
  while (in >> name >> kb >> unit)
    if (name == "MemAvailable:") return kb * 1024;
  return 0;
}
// Estimated time steps of a run: warn above, refuse above.
constexpr double kManySteps = 2e7;
constexpr double kMaxSteps = 1e9;

std::vector<KeyDef> make_defs() {
  std::vector<KeyDef> defs;
  {
    KeyDef d{"name", "", "scene name, shown in captions and summaries", Type::text, 1.0, 0, 0, false, {}, {}, {},
             {},     {}};
    d.set_text = [](Scene& s, const std::string& v) { s.name = v; };
    d.get_text = [](const Scene& s) { return s.name; };
    defs.push_back(d);
  }
  text_key(
      defs, "fabric.weave",
      "plain (balanced plain weave) or single_yarn (one straight yarn along y, clamped at both ends)",
      {"plain", "single_yarn"},
      [](Scene& s, const std::string& v) { s.fabric.weave = v == "plain" ? Weave::plain : Weave::single_yarn; },
      [](const Scene& s) { return std::string(to_string(s.fabric.weave)); });
  NUM("fabric.width_mm", "mm", "fabric size along x (weft direction)", 1e-3, 0, true, inf, fabric.width_m);
  NUM("fabric.length_mm", "mm", "fabric size along y (warp direction)", 1e-3, 0, true, inf, fabric.length_m);
  NUM("fabric.spacing_mm", "mm", "L0: horizontal distance between neighbouring nodes of a yarn", 1e-3, 0, true, inf,
      fabric.spacing_m);
  NUM("fabric.crossing_gap_mm", "mm", "L1: vertical distance between the two nodes at a crossing", 1e-3, 0, false, inf,
      fabric.crossing_gap_m);
  NUM("fabric.node_mass_g", "g", "lumped mass m of one yarn node", 1e-3, 0, true, inf, fabric.node_mass_kg);
  NUM("fabric.thickness_mm", "mm", "fabric thickness; the yarn contact diameter D is half of it", 1e-3, 0, true, inf,
      fabric.thickness_m);
  {
    KeyDef d{"fabric.clamped",
             "",
             "clamped edges: comma list of left,right (x = -W/2, +W/2), bottom,top (y = -L/2, +L/2), or all / none",
             Type::text,
             1.0,
             0,
             0,
             false,
             {},
             {},
             {},
             {},
             {}};
    d.set_text = [](Scene& s, const std::string& v) {
      ClampedEdges c{false, false, false, false};
      std::stringstream ss(v);
      std::string item;
      while (std::getline(ss, item, ',')) {
        item.erase(std::remove_if(item.begin(), item.end(), ::isspace), item.end());
        if (item == "left")
          c.left = true;
        else if (item == "right")
          c.right = true;
        else if (item == "bottom")
          c.bottom = true;
        else if (item == "top")
          c.top = true;
        else if (item == "all")
          c = {true, true, true, true};
        else if (item == "none" || item.empty()) {
        } else
          throw std::invalid_argument("unknown edge '" + item + "' (use left, right, bottom, top, all or none)");
      }
      s.fabric.clamped = c;
    };
    d.get_text = [](const Scene& s) { return s.fabric.clamped.to_string(); };
    defs.push_back(d);
  }
  text_key(
      defs, "fabric.clamp",
      "rigid (the paper: no yarn leaves a clamp) or slipping (the clamp feeds yarn out once the yarn pulls harder "
      "than fabric.clamp_grip_n; a test rig's clamp, docs/MODEL.md §7)",
      {"rigid", "slipping"},
      [](Scene& s, const std::string& v) { s.fabric.clamp = v == "rigid" ? ClampKind::rigid : ClampKind::slipping; },
      [](const Scene& s) { return std::string(to_string(s.fabric.clamp)); });
  NUM("fabric.clamp_grip_n", "N",
      "slipping clamp: pull on one real yarn at which it slides through the clamp (Coulomb friction of the clamp "
      "faces; about 10-250 N for pneumatic to bolted clamps, above the yarn's break load ~290 N it never slips)",
      1, 0, true, inf, fabric.clamp_grip_n);
  NUM("fabric.clamp_depth_mm", "mm",
      "slipping clamp: the length of yarn the clamp holds (its jaws' width, about 10-50 mm); once that much has "
      "been fed out the yarn has left the clamp and pulls on nothing",
      1e-3, 0, true, inf, fabric.clamp_depth_m);
  text_key(
      defs, "fabric.crossing_compression",
      "rigid (crossing yarns keep their centre distance D under any load, the paper read literally) or "
      "hyperbolic (the distance falls from its rest value towards fabric.flattened_gap_mm as the normal force "
      "grows: c = c_min + (c0 - c_min) / (1 + f / F_half))",
      {"rigid", "hyperbolic"},
      [](Scene& s, const std::string& v) {
        s.fabric.crossing_compression = v == "rigid" ? CrossingCompression::rigid : CrossingCompression::hyperbolic;
      },
      [](const Scene& s) { return std::string(to_string(s.fabric.crossing_compression)); });
  NUM("fabric.flattened_gap_mm", "mm",
      "c_min: centre distance of two crossing yarns pressed fully flat (fibres packed); below D", 1e-3, 0, true, inf,
      fabric.flattened_gap_m);
  NUM("fabric.compression_force_n", "N",
      "F_half: normal force per crossing that closes half of the compressible distance D - c_min", 1, 0, true, inf,
      fabric.compression_force_n);
  NUM("fabric.packed_gap_mm", "mm",
      "c_pack: centre distance of two crossing yarns whose fibres are packed (end of the packing stage, "
      "before the fibres themselves flatten); below D; at or below c_min the law has one stage",
      1e-3, 0, true, inf, fabric.packed_gap_m);
  NUM("fabric.flattening_force_n", "N",
      "F_flat: normal force per crossing that closes half of the flattening stage c_pack - c_min", 1, 0, true, inf,
      fabric.flattening_force_n);
  INT("fabric.yarns_per_element", "", "k: real yarns lumped into one modelled yarn (mesh coarsening; 1 = every yarn)",
      1, 16, fabric.yarns_per_element);
  INT("fabric.far_yarns_per_element", "",
      "graded mesh: real yarns per modelled yarn outside the band fabric.full_resolution_mm around the strike point "
      "(1 = every yarn everywhere)",
      1, 16, fabric.far_yarns_per_element);
  NUM("fabric.full_resolution_mm", "mm",
      "graded mesh: half-width of the bands through the strike point in which every real yarn is modelled", 1e-3, 0,
      false, inf, fabric.full_resolution_m);
  NUM("fabric.clamp_resolution_mm", "mm",
      "graded mesh: width of the bands along clamped edges in which every real yarn is modelled (the clamped yarns "
      "break there near the ballistic limit)",
      1e-3, 0, false, inf, fabric.clamp_resolution_m);
  text_key(
      defs, "yarn.material", "zener (viscoelastic, Eq 23) or elastic (linear, modulus_pa)", {"zener", "elastic"},
      [](Scene& s, const std::string& v) { s.yarn.material = v == "zener" ? Material::zener : Material::elastic; },
      [](const Scene& s) { return std::string(to_string(s.yarn.material)); });
  NUM("yarn.modulus_pa", "Pa", "Young's modulus E of the elastic material", 1, 0, true, inf, yarn.modulus_pa);
  NUM("yarn.k1_pa", "Pa", "Zener K1: spring in series (instantaneous modulus)", 1, 0, true, inf, yarn.k1_pa);
  NUM("yarn.k2_pa", "Pa", "Zener K2: spring of the Kelvin-Voigt unit", 1, 0, true, inf, yarn.k2_pa);
  NUM("yarn.damping_pa_s", "Pa s", "Zener dashpot mu_d", 1, 0, true, inf, yarn.damping_pa_s);
  NUM("yarn.density_kg_m3", "kg/m^3", "yarn density rho (wave speed sqrt(E/rho))", 1, 0, true, inf, yarn.density_kg_m3);
  NUM("yarn.area_m2", "m^2", "yarn cross-section A", 1, 0, true, inf, yarn.area_m2);
  NUM("yarn.failure_strain", "", "element strain at which a yarn element breaks", 1, 0, true, 1.0, yarn.failure_strain);
  BOOL("yarn.breakable", "false: elements never break (energy checks)", yarn.breakable);
  NUM("yarn.friction", "", "yarn-yarn Coulomb friction coefficient mu", 1, 0, false, 10.0, yarn.friction);
  NUM("yarn.bending_fraction", "",
      "stiffness of the compression-only bending springs / element axial stiffness (paper: 0.05)", 1, 0, false, 1.0,
      yarn.bending_fraction);
  NUM("yarn.crimp_modulus_fraction", "",
      "pin-jointed model: stiffness at the start of the crimp stage (the yarn straightening its crimp, "
      "sqrt(L0^2 + L1^2) / L0 - 1 of stretch), as a fraction of the yarn modulus; it rises to the full modulus "
      "as the crimp is taken up",
      1, 0, false, 0.9, yarn.crimp_modulus_fraction);
  NUM("yarn.crimp_damping", "",
      "pin-jointed model: damping of a taut element's stretch (the dissipation of crimp interchange, which the "
      "pinned crossings cannot slide to produce), as a fraction of critical at the elements' highest axial "
      "mode: its force gains beta E A d(strain)/dt, beta = this x L / c; 0 = none",
      1, 0, false, 1.0, yarn.crimp_damping);
  text_key(
      defs, "projectile.shape", "sphere, cylinder (flat-faced) or cone", {"sphere", "cylinder", "cone"},
      [](Scene& s, const std::string& v) {
        s.projectile.shape = v == "sphere"     ? ShapeKind::sphere
                             : v == "cylinder" ? ShapeKind::cylinder
                                               : ShapeKind::cone;
      },
      [](const Scene& s) { return std::string(to_string(s.projectile.shape)); });
  NUM("projectile.diameter_mm", "mm", "projectile diameter", 1e-3, 0, true, inf, projectile.diameter_m);
  NUM("projectile.length_mm", "mm", "cylinder length / cone height", 1e-3, 0, true, inf, projectile.length_m);
  NUM("projectile.mass_g", "g", "projectile mass M", 1e-3, 0, true, inf, projectile.mass_kg);
  NUM("projectile.velocity_mps", "m/s", "impact velocity V0", 1, 0, true, inf, projectile.velocity_mps);
  NUM("projectile.friction", "", "projectile-yarn friction coefficient mu_p", 1, 0, false, 10.0, projectile.friction);
  NUM("projectile.offset_x_mm", "mm", "strike point x offset from the fabric centre", 1e-3, -inf, false, inf,
      projectile.offset_x_m);
  NUM("projectile.offset_y_mm", "mm", "strike point y offset from the fabric centre", 1e-3, -inf, false, inf,
      projectile.offset_y_m);
  NUM("projectile.obliquity_deg", "deg", "angle of the flight path from the fabric normal (in the x-z plane)", 1, 0,
      false, 80, projectile.obliquity_deg);
  text_key(
      defs, "solver.model",
      "sliding (yarns slide with friction, the paper's model) or pin_jointed (one shared node per crossing)",
      {"sliding", "pin_jointed"},
      [](Scene& s, const std::string& v) {
        s.solver.model = v == "sliding" ? ContactModel::sliding : ContactModel::pin_jointed;
      },
      [](const Scene& s) { return std::string(to_string(s.solver.model)); });
  NUM("solver.dt_factor", "", "alpha of Eq 4: dt = alpha L / c", 1, 0, true, 10.0, solver.dt_factor);
  INT("solver.contact_iterations", "", "N: yarn contact correction passes per step (Eq 16-17)", 1, 64,
      solver.contact_iterations);
  BOOL("solver.split_penetration",
       "true: penetration left from earlier steps is removed by moving the nodes (no energy injected); false: the "
       "paper's velocity-only correction",
       solver.split_penetration);
  BOOL("solver.decide_passing",
       "true: end the run as perforated once the projectile is passing through (some element broken, held only by "
       "yarns with no intact path to a clamp, above 1 % of its impact speed, and at its present drag it would travel "
       "further than the "
       "fabric's largest half-size before stopping, for 100 us); the fast limit search sets it (docs/MODEL.md §8)",
       solver.decide_passing);
  BOOL("solver.projectile_holds",
       "true: a node the projectile pushed out does not yield into it under yarn contact (the push goes to the "
       "projectile); false: the yarn contact moves it freely",
       solver.projectile_holds);
  NUM("solver.friction_penalty", "", "alpha_f of the stick penalty K = alpha_f m / dt^2 (Eq 12), <= 1", 1, 0, true, 1.0,
      solver.friction_penalty);
  text_key(
      defs, "solver.symmetry", "auto (smallest model the scene's symmetry allows) or full", {"auto", "full"},
      [](Scene& s, const std::string& v) {
        s.solver.symmetry = v == "auto" ? SymmetryMode::automatic : SymmetryMode::full;
      },
      [](const Scene& s) { return std::string(s.solver.symmetry == SymmetryMode::automatic ? "auto" : "full"); });
  text_key(
      defs, "solver.precision", "double or float: floating-point precision of the state", {"double", "float"},
      [](Scene& s, const std::string& v) {
        s.solver.precision = v == "double" ? Precision::double_precision : Precision::single_precision;
      },
      [](const Scene& s) {
        return std::string(s.solver.precision == Precision::double_precision ? "double" : "float");
      });
  NUM("solver.end_time_us", "us",
      "latest simulated time (a run also ends at perforation, rebound or caught); auto: until one of those, at "
      "most solver.max_end_time_us",
      1e-6, 0, true, 1e5, solver.end_time_s);
  defs.back().set_number = [](Scene& s, double v) {
    s.solver.end_time_s = v;
    s.solver.end_time_auto = false;
  };
  defs.back().set_auto = [](Scene& s) {
    s.solver.end_time_auto = true;
    s.solver.end_time_s = s.solver.max_end_time_s;
  };
  defs.back().is_auto = [](const Scene& s) { return s.solver.end_time_auto; };
  NUM("solver.max_end_time_us", "us",
      "cap of an auto end time, and how far ballistic-limit searches extend a run that reached its end time "
      "undecided",
      1e-6, 0, true, 1e5, solver.max_end_time_s);
  defs.back().set_number = [](Scene& s, double v) {
    s.solver.max_end_time_s = v;
    if (s.solver.end_time_auto) s.solver.end_time_s = v;
  };
  INT("solver.threads", "", "worker threads for the step (0 = all cores)", 0, 256, solver.threads);
  BOOL("solver.simd",
       "true: the yarn contact's geometry and the Zener elements are computed four at a time in AVX2 lanes where "
       "the processor has them (double precision; the same numbers bit for bit); false: one at a time",
       solver.simd);
  NUM("solver.snap_damping", "",
      "damping of a slack yarn element snapping taut, as a fraction of critical at the elements' highest axial "
      "mode (in that step its stress gains beta E strain rate, beta = this x L / c); 0 = none",
      1, 0, false, 0.2, solver.snap_damping);
  NUM("solver.max_balance_error", "",
      "a run whose energy ledger misses the initial energy by more than this fraction is declared diverged", 1, 0, true,
      1e3, solver.max_balance_error);
  NUM("solver.max_search_lost", "",
      "a run in which the nearest-pair search loses track (yarns sliding more than one node in one step) at more than "
      "this fraction of the crossings in one step is declared diverged; 1 = never",
      1, 0, false, 1.0, solver.max_search_lost);
  NUM("output.history_interval_us", "us", "time between rows of history.csv", 1e-6, 0, true, 1e6,
      output.history_interval_s);
  BOOL("output.progress", "print a progress line on a terminal", output.progress);
  return defs;
}
#undef NUM
#undef INT
#undef BOOL

const std::vector<KeyDef>& defs() {
  static const std::vector<KeyDef> d = make_defs();
  return d;
}

const KeyDef* find_def(const std::string& key) {
  for (const auto& d : defs())
    if (d.key == key) return &d;
  return nullptr;
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string did_you_mean(const std::string& key) {
  const KeyDef* best = nullptr;
  size_t best_d = 1000;
  for (const auto& d : defs()) {
    size_t e = edit_distance(key, d.key);
    // Also match the last component alone (`friction` under the wrong section).
    auto dot = d.key.rfind('.');
    auto kdot = key.rfind('.');
    if (dot != std::string::npos && kdot != std::string::npos && d.key.substr(dot) == key.substr(kdot))
      e = std::min<size_t>(e, 2);
    if (e < best_d) best_d = e, best = &d;
  }
  if (best && best_d <= std::max<size_t>(3, key.size() / 3)) return " (did you mean '" + best->key + "'?)";
  return "";
}

std::string fmt(double v) {
  std::ostringstream o;
  o.precision(12);
  o << v;
  return o.str();
}

// Values that look like they were given in another unit: the usual range of a key (in
// the key's own unit) and the units people mix it up with. A value outside the usual
// range that lands inside it once converted from one of those units gets a hint.
struct UnitSlip {
  const char* key;
  double lo, hi;                                    // usual range, in the key's unit
  std::vector<std::pair<const char*, double>> alt;  // (unit, factor to the key's unit)
};

const std::vector<UnitSlip>& unit_slips() {
  static const std::vector<UnitSlip> t = {
      {"fabric.width_mm", 2, 2000, {{"m", 1e3}, {"cm", 10}}},
      {"fabric.length_mm", 2, 2000, {{"m", 1e3}, {"cm", 10}}},
      {"fabric.spacing_mm", 0.05, 20, {{"m", 1e3}, {"um", 1e-3}}},
      {"fabric.crossing_gap_mm", 0.005, 5, {{"m", 1e3}, {"um", 1e-3}}},
      {"fabric.thickness_mm", 0.01, 20, {{"m", 1e3}, {"um", 1e-3}}},
      {"fabric.flattened_gap_mm", 0.005, 5, {{"m", 1e3}, {"um", 1e-3}}},
      {"fabric.compression_force_n", 1e-3, 1e4, {{"kN", 1e3}, {"mN", 1e-3}}},
      {"fabric.packed_gap_mm", 0.005, 5, {{"m", 1e3}, {"um", 1e-3}}},
      {"fabric.flattening_force_n", 1e-3, 1e5, {{"kN", 1e3}, {"mN", 1e-3}}},
      {"projectile.diameter_mm", 0.5, 300, {{"m", 1e3}, {"cm", 10}}},
      {"projectile.length_mm", 0.5, 1000, {{"m", 1e3}, {"cm", 10}}},
      {"projectile.mass_g", 0.05, 1e5, {{"kg", 1e3}, {"mg", 1e-3}}},
      {"projectile.velocity_mps", 1, 5000, {{"km/s", 1e3}}},
      {"yarn.k1_pa", 1e8, 1e13, {{"GPa", 1e9}, {"MPa", 1e6}}},
      {"yarn.k2_pa", 1e8, 1e14, {{"GPa", 1e9}, {"MPa", 1e6}}},
      {"yarn.modulus_pa", 1e8, 1e13, {{"GPa", 1e9}, {"MPa", 1e6}}},
      {"yarn.density_kg_m3", 100, 25000, {{"g/cm^3", 1e3}}},
      {"yarn.area_m2", 1e-12, 1e-4, {{"mm^2", 1e-6}}},
      {"yarn.failure_strain", 1e-3, 1, {{"%", 1e-2}}},
      {"solver.end_time_us", 0.5, 1e5, {{"s", 1e6}, {"ms", 1e3}, {"ns", 1e-3}}},
      {"output.history_interval_us", 1e-3, 1e3, {{"s", 1e6}, {"ns", 1e-3}}},
  };
  return t;
}

// "" or "; it looks like a value in m: 0.000844 m = 0.844 mm".
std::string units_hint(const std::string& key, double v) {
  for (const auto& u : unit_slips()) {
    if (key != u.key) continue;
    if (!(v > 0) || (v >= u.lo && v <= u.hi)) return "";
    for (const auto& [unit, factor] : u.alt) {
      const double c = v * factor;
      if (c >= u.lo && c <= u.hi) {
        const auto* d = find_def(key);
        const std::string own = d && !d->unit.empty() ? d->unit : "";
        return "; it looks like a value in " + std::string(unit) + " (" + fmt(v) + " " + unit + " = " + fmt(c) +
               (own.empty() ? "" : " " + own) + "; the key is in " + (own.empty() ? "plain numbers" : own) + ")";
      }
    }
    return "";
  }
  return "";
}

std::string fmt3(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

// Apply one value to the scene, with the key's checks. `raw` is the value as the user
// wrote it (for messages).
void apply_number(Scene& s, const KeyDef& d, double v, const std::string& where) {
  if (std::isnan(v)) throw SceneError(d.key, where, "is NaN; give a number" + (d.unit.empty() ? "" : " in " + d.unit));
  if (std::isinf(v)) throw SceneError(d.key, where, "is infinite; give a finite number");
  if (d.type == Type::integer && v != std::floor(v))
    throw SceneError(d.key, where, "must be a whole number, got " + fmt(v));
  const bool below = d.min_exclusive ? v <= d.min : v < d.min;
  if (below || v > d.max) {
    std::string range;
    if (below && d.min == 0)
      range = d.min_exclusive ? "must be positive" : "must not be negative";
    else if (below)
      range = std::string("must be ") + (d.min_exclusive ? "> " : ">= ") + fmt(d.min);
    else
      range = "must be <= " + fmt(d.max);
    throw SceneError(d.key, where,
                     range + ", got " + fmt(v) + (d.unit.empty() ? "" : " " + d.unit) + units_hint(d.key, v));
  }
  d.set_number(s, v * d.scale);
}

// Well-formed UTF-8 (no overlong forms, no surrogates, nothing past U+10FFFF): what a
// TOML file can hold, so that every text value can be written back to scene.toml.
bool valid_utf8(const std::string& v) {
  size_t i = 0;
  while (i < v.size()) {
    const unsigned char c = v[i];
    int n;
    unsigned cp;
    if (c < 0x80)
      n = 0, cp = c;
    else if ((c >> 5) == 0x6)
      n = 1, cp = c & 0x1f;
    else if ((c >> 4) == 0xe)
      n = 2, cp = c & 0x0f;
    else if ((c >> 3) == 0x1e)
      n = 3, cp = c & 0x07;
    else
      return false;
    if (i + n >= v.size() && n > 0) return false;
    for (int k = 1; k <= n; ++k) {
      const unsigned char cc = v[i + k];
      if ((cc >> 6) != 0x2) return false;
      cp = (cp << 6) | (cc & 0x3f);
    }
    static const unsigned min_cp[] = {0, 0x80, 0x800, 0x10000};
    if (cp < min_cp[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += n + 1;
  }
  return true;
}

void apply_text(Scene& s, const KeyDef& d, const std::string& v, const std::string& where) {
  if (!valid_utf8(v) || v.find('\0') != std::string::npos) throw SceneError(d.key, where, "is not valid UTF-8 text");
  if (!d.choices.empty() && std::find(d.choices.begin(), d.choices.end(), v) == d.choices.end()) {
    std::string list;
    for (const auto& c : d.choices) list += (list.empty() ? "" : ", ") + c;
    throw SceneError(d.key, where, "unknown value '" + v + "' (choose one of: " + list + ")");
  }
  try {
    d.set_text(s, v);
  } catch (const std::invalid_argument& e) {
    throw SceneError(d.key, where, e.what());
  }
}

const char* type_name(Type t) {
  switch (t) {
    case Type::number:
      return "a number";
    case Type::integer:
      return "a whole number";
    case Type::boolean:
      return "true or false";
    case Type::text:
      return "a string";
  }
  return "?";
}

void apply_node(Scene& s, const std::string& key, const toml::node& node, const std::string& file) {
  std::string where = file + ":" + std::to_string(node.source().begin.line);
  const KeyDef* d = find_def(key);
  if (!d) throw SceneError(key, where, "unknown key" + did_you_mean(key));
  s.origin[key] = where;
  switch (d->type) {
    case Type::number:
    case Type::integer:
      if (auto v = node.value<double>(); v && (node.is_number())) {
        apply_number(s, *d, *v, where);
        return;
      }
      if (auto t = node.value<std::string>(); t && node.is_string() && d->set_auto) {
        if (*t != "auto") throw SceneError(key, where, "expected a number or \"auto\", got '" + *t + "'");
        d->set_auto(s);
        return;
      }
      break;
    case Type::boolean:
      if (auto v = node.value<bool>(); v && node.is_boolean()) {
        d->set_number(s, *v ? 1 : 0);
        return;
      }
      break;
    case Type::text:
      if (auto v = node.value<std::string>(); v && node.is_string()) {
        apply_text(s, *d, *v, where);
        return;
      }
      break;
  }
  throw SceneError(key, where, std::string("wrong type: expected ") + type_name(d->type));
}

void walk(Scene& s, const toml::table& table, const std::string& prefix, const std::string& file) {
  for (const auto& [k, node] : table) {
    std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    if (const auto* sub = node.as_table()) {
      bool is_section = false;
      for (const auto& d : defs())
        if (d.key.rfind(key + ".", 0) == 0) is_section = true;
      if (!is_section) {
        std::string where = file + ":" + std::to_string(node.source().begin.line);
        throw SceneError(key, where, "unknown section (sections are fabric, yarn, projectile, solver, output)");
      }
      walk(s, *sub, key, file);
    } else {
      apply_node(s, key, node, file);
    }
  }
}

void apply_override(Scene& s, const std::string& kv) {
  const std::string where = "--set " + kv;
  auto eq = kv.find('=');
  if (eq == std::string::npos || eq == 0)
    throw SceneError("", "--set", "'" + kv + "' is not of the form section.key=value");
  std::string key = kv.substr(0, eq), val = kv.substr(eq + 1);
  auto trim = [](std::string& t) {
    while (!t.empty() && isspace((unsigned char)t.back())) t.pop_back();
    while (!t.empty() && isspace((unsigned char)t.front())) t.erase(t.begin());
  };
  trim(key);
  trim(val);
  const KeyDef* d = find_def(key);
  if (!d) throw SceneError(key, "--set", "unknown key" + did_you_mean(key));
  s.origin[key] = "--set";
  switch (d->type) {
    case Type::number:
    case Type::integer: {
      std::string low = val;
      std::transform(low.begin(), low.end(), low.begin(), ::tolower);
      double v;
      if (low == "auto" && d->set_auto) {
        d->set_auto(s);
        return;
      }
      if (low == "nan")
        v = std::numeric_limits<double>::quiet_NaN();
      else if (low == "inf" || low == "+inf")
        v = inf;
      else if (low == "-inf")
        v = -inf;
      else {
        char* end = nullptr;
        v = std::strtod(val.c_str(), &end);
        if (val.empty() || end != val.c_str() + val.size())
          throw SceneError(key, "--set",
                           "wrong type: expected " + std::string(type_name(d->type)) + ", got '" + val + "'");
      }
      apply_number(s, *d, v, "--set");
      return;
    }
    case Type::boolean:
      if (val == "true" || val == "1")
        d->set_number(s, 1);
      else if (val == "false" || val == "0")
        d->set_number(s, 0);
      else
        throw SceneError(key, "--set", "wrong type: expected true or false, got '" + val + "'");
      return;
    case Type::text:
      if (val.size() >= 2 && (val.front() == '"' || val.front() == '\'') && val.back() == val.front())
        val = val.substr(1, val.size() - 2);
      apply_text(s, *d, val, "--set");
      return;
  }
}

}  // namespace

const std::vector<SceneKeyInfo>& scene_keys() {
  static const std::vector<SceneKeyInfo> info = [] {
    std::vector<SceneKeyInfo> v;
    const Scene built_in;
    for (const auto& d : defs()) {
      SceneKeyInfo k{d.key, d.unit, d.description, "", ""};
      if (d.is_auto && d.is_auto(built_in))
        k.default_value = "auto";
      else if (d.type == Type::text)
        k.default_value = "\"" + d.get_text(built_in) + "\"";
      else if (d.type == Type::boolean)
        k.default_value = d.get_number(built_in) != 0 ? "true" : "false";
      else
        k.default_value = fmt(d.get_number(built_in) / d.scale);
      if (d.type == Type::text) {
        for (const auto& c : d.choices) k.range += (k.range.empty() ? "" : " | ") + c;
      } else if (d.type != Type::boolean) {
        const bool lo = std::isfinite(d.min), hi = std::isfinite(d.max);
        if (lo && hi)
          k.range = (d.min_exclusive ? "(" : "[") + fmt(d.min) + ", " + fmt(d.max) + "]";
        else if (lo)
          k.range = (d.min_exclusive ? "> " : ">= ") + fmt(d.min);
        else if (hi)
          k.range = "<= " + fmt(d.max);
        if (d.set_auto) k.range += " or auto";
      }
      v.push_back(std::move(k));
    }
    return v;
  }();
  return info;
}

Scene parse_scene(const std::string& toml_text, const std::string& source_name,
                  const std::vector<std::string>& overrides) {
  Scene s;
  s.source = source_name;
  toml::table table;
  try {
    table = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    std::string where = source_name + ":" + std::to_string(e.source().begin.line);
    throw SceneError("", where, std::string("TOML syntax error: ") + std::string(e.description()));
  }
  walk(s, table, "", source_name.empty() ? "scene" : source_name);
  for (const auto& kv : overrides) apply_override(s, kv);
  validate_scene(s);
  return s;
}

Scene load_scene(const std::string& path, const std::vector<std::string>& overrides) {
  if (path.empty()) return parse_scene("", "", overrides);
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw SceneError("", path, "is a folder, not a scene file (a run's output folder holds its scene.toml)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError("", path, "cannot open scene file (does it exist and is it readable?)");
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  // An empty file (or /dev/null) would silently be the built-in scene: refuse it.
  bool content = false;
  std::istringstream lines(text);
  for (std::string line; !content && std::getline(lines, line);) {
    const auto first = line.find_first_not_of(" \t\r");
    content = first != std::string::npos && line[first] != '#';
  }
  if (!content)
    throw SceneError("", path,
                     "holds no scene keys (empty or only comments); give a scene file such as " + default_scene_path() +
                         ", or leave SCENE out for the default scene");
  return parse_scene(text, path, overrides);
}

void validate_scene(Scene& s) {
  s.warnings.clear();
  const std::string file = s.source.empty() ? "scene" : s.source;
  // Where a key's value came from: its line, `--set`, or the file when it kept its default.
  auto where = [&](const std::string& key) {
    auto it = s.origin.find(key);
    return it != s.origin.end() ? it->second : file;
  };
  // A hard error about `key`, with a units hint when its value looks like another unit.
  auto fail = [&](const std::string& key, const std::string& problem) {
    std::string hint;
    if (const KeyDef* d = find_def(key); d && d->get_number) hint = units_hint(key, d->get_number(s) / d->scale);
    throw SceneError(key, where(key), problem + hint);
  };
  // Non-negative / positive / NaN checks of every value (overrides applied to defaults,
  // values that came from code rather than text).
  for (const auto& d : defs()) {
    if (!d.get_number) continue;
    double v = d.get_number(s) / d.scale;
    if (d.type == Type::boolean) continue;
    if (d.is_auto && d.is_auto(s)) continue;
    apply_number(s, d, v, where(d.key));  // re-applies the same value: validates it
  }
  const auto& f = s.fabric;
  const auto& p = s.projectile;
  const double L0 = f.spacing_m * f.yarns_per_element;
  if (f.weave == Weave::plain) {
    if (f.width_m < 2 * L0 || f.length_m < 2 * L0)
      fail(f.width_m < 2 * L0 ? "fabric.width_mm" : "fabric.length_mm",
           "the fabric must span at least two yarn spacings (fabric.spacing_mm x fabric.yarns_per_element) each way");
    // Too big: blame the size when it is what the user changed, else the spacing.
    const Scene built_in;
    const bool size_changed = f.width_m != built_in.fabric.width_m || f.length_m != built_in.fabric.length_m;
    const std::string size_key = f.width_m >= f.length_m ? "fabric.width_mm" : "fabric.length_mm";
    const std::string too_big_key = size_changed ? size_key : "fabric.spacing_mm";
    const std::string sizes =
        "fabric.width_mm = " + fmt(f.width_m * 1e3) + ", fabric.length_mm = " + fmt(f.length_m * 1e3) +
        " at fabric.spacing_mm = " + fmt(f.spacing_m * 1e3) +
        (f.yarns_per_element > 1 ? " x fabric.yarns_per_element = " + fmt(f.yarns_per_element) : "");
    if (f.width_m / L0 > 4000 || f.length_m / L0 > 4000)
      fail(too_big_key, "more than 4000 yarns per direction (" + fmt(std::round(std::max(f.width_m, f.length_m) / L0)) +
                            ", from " + sizes + "); this would not fit in memory");
    // Memory: nodes the solver will hold (after symmetry) at the measured bytes per node.
    const SymmetryChoice sym = choose_symmetry(s);
    const double hx = std::floor(f.width_m / 2 / L0 + 1e-9), hy = std::floor(f.length_m / 2 / L0 + 1e-9);
    const double nx = sym.mirror_x ? hx + 1 : 2 * hx + 1, ny = sym.mirror_y ? hy + 1 : 2 * hy + 1;
    const double nodes = nx * ny * (s.solver.model == ContactModel::sliding ? 2 : 1);
    const double need = nodes * kBytesPerNode;
    const double avail = available_memory_bytes();
    if (avail > 0 && need > avail)
      fail(too_big_key, "the fabric (" + sizes + ") needs about " + fmt3(need / 1e9) + " GB for its " + fmt3(nodes) +
                            " modelled nodes, and " + fmt3(avail / 1e9) +
                            " GB of memory is available; make it smaller or coarser (fabric.yarns_per_element)");
  } else {
    if (f.length_m < 2 * L0) fail("fabric.length_mm", "the yarn must span at least two node spacings");
    if (f.length_m / L0 > 1e6)
      fail("fabric.spacing_mm", "more than a million nodes along the yarn (" + fmt(std::round(f.length_m / L0)) + ")");
  }
  if (f.far_yarns_per_element > 1 && f.yarns_per_element > 1)
    fail("fabric.far_yarns_per_element",
         "a graded mesh lumps only outside the full-resolution band; it cannot be combined "
         "with fabric.yarns_per_element = " +
             fmt(f.yarns_per_element) + " (set one of them to 1)");
  if (f.far_yarns_per_element > 1 && f.weave == Weave::single_yarn)
    fail("fabric.far_yarns_per_element", "a single yarn has no crossing yarns to lump (set it to 1)");
  if (f.crossing_gap_m > L0) fail("fabric.crossing_gap_mm", "L1 larger than the node spacing L0 is not a woven fabric");
  if (f.crossing_compression == CrossingCompression::hyperbolic && f.flattened_gap_m >= 0.5 * f.thickness_m)
    fail("fabric.flattened_gap_mm", "the flattened centre distance (" + fmt3(f.flattened_gap_m * 1e3) +
                                        " mm) must be below the rest distance D = fabric.thickness_mm / 2 = " +
                                        fmt3(0.5 * f.thickness_m * 1e3) + " mm");
  if (f.crossing_compression == CrossingCompression::hyperbolic && f.packed_gap_m >= 0.5 * f.thickness_m)
    fail("fabric.packed_gap_mm", "the packed centre distance (" + fmt3(f.packed_gap_m * 1e3) +
                                     " mm) must be below the rest distance D = fabric.thickness_mm / 2 = " +
                                     fmt3(0.5 * f.thickness_m * 1e3) + " mm");
  // The projectile against the fabric as a whole (after the fabric itself): a clearer message than "does not
  // fit at the strike point" when no strike point could work.
  const double fabric_min = f.weave == Weave::plain ? std::min(f.width_m, f.length_m) : f.length_m;
  if (p.diameter_m >= fabric_min)
    fail("projectile.diameter_mm",
         "the projectile (" + fmt(p.diameter_m * 1e3) + " mm) is larger than the fabric (" +
             (f.weave == Weave::plain ? fmt(f.width_m * 1e3) + " x " + fmt(f.length_m * 1e3) : fmt(f.length_m * 1e3)) +
             " mm); make the fabric larger or the projectile smaller");
  const double half_x = f.weave == Weave::plain ? f.width_m / 2 : f.length_m / 2;
  if (std::abs(p.offset_x_m) + p.diameter_m / 2 >= half_x ||
      std::abs(p.offset_y_m) + p.diameter_m / 2 >= f.length_m / 2) {
    const bool off = p.offset_x_m != 0 || p.offset_y_m != 0;
    fail(off ? (std::abs(p.offset_x_m) + p.diameter_m / 2 >= half_x ? "projectile.offset_x_mm"
                                                                    : "projectile.offset_y_mm")
             : "projectile.diameter_mm",
         "the projectile does not fit inside the fabric at the strike point (check diameter and offsets)");
  }
  if (s.solver.dt_factor > 1.0)
    s.warnings.push_back("solver.dt_factor = " + fmt(s.solver.dt_factor) +
                         " is above 1: beyond the explicit stability limit of Eq 4; the run will likely diverge");
  // The Zener constants are a fit to Gu's tests up to 5.7 % strain; far beyond that the
  // model is extrapolating (the hard limit, 1, is in the key table).
  if (s.yarn.material == Material::zener && s.yarn.failure_strain > 0.2)
    s.warnings.push_back("yarn.failure_strain = " + fmt(s.yarn.failure_strain) +
                         " is beyond the small-strain range the Zener fit (Gu's data, up to 5.7 %) covers");
  // Node mass against density x area x element length (the paper's m = rho A L): more
  // than 25 % off warns, more than a factor 3 is an error.
  const double elem_len = std::sqrt(f.spacing_m * f.spacing_m + f.crossing_gap_m * f.crossing_gap_m);
  const double m_expected = s.yarn.density_kg_m3 * s.yarn.area_m2 * elem_len;
  const double ratio = f.node_mass_kg / m_expected;
  if (ratio > kNodeMassErrorFactor || ratio < 1.0 / kNodeMassErrorFactor) {
    const std::string problem = "node mass " + fmt3(f.node_mass_kg * 1e3) +
                                " g is inconsistent with density x area x element length = " + fmt3(m_expected * 1e3) +
                                " g (more than " + fmt(kNodeMassErrorFactor) + "x apart)";
    // Blame the value that looks like a unit slip, if one does.
    for (const char* key : {"yarn.density_kg_m3", "yarn.area_m2", "fabric.spacing_mm"}) {
      const KeyDef* d = find_def(key);
      if (!units_hint(key, d->get_number(s) / d->scale).empty()) fail(key, problem);
    }
    std::string hint;
    if (ratio / 1e3 > 0.8 && ratio / 1e3 < 1.25) hint = "; it looks like a value in mg (the key is in g)";
    if (ratio * 1e3 > 0.8 && ratio * 1e3 < 1.25) hint = "; it looks like a value in kg (the key is in g)";
    throw SceneError("fabric.node_mass_g", where("fabric.node_mass_g"), problem + hint);
  }
  if (ratio > 1 + kNodeMassWarnFraction || ratio < 1 / (1 + kNodeMassWarnFraction))
    s.warnings.push_back("fabric.node_mass_g differs from density x area x element length by " +
                         fmt(std::round((ratio - 1) * 100)) + " % (tolerance " + fmt(kNodeMassWarnFraction * 100) +
                         " %)");
  if (f.weave == Weave::plain && p.diameter_m > 0.9 * std::min(f.width_m, f.length_m))
    s.warnings.push_back("the projectile is nearly as large as the fabric");
  // Run length: dt = alpha L / c (Eq 4) with the shortest element about L0. A run that
  // needs billions of steps is almost always a unit slip in a modulus, density or time.
  const double E = s.yarn.material == Material::zener ? s.yarn.k1_pa : s.yarn.modulus_pa;
  const double c = std::sqrt(E / s.yarn.density_kg_m3);
  const double steps = s.solver.end_time_s / (s.solver.dt_factor * std::min(L0, elem_len) / c);
  const std::string modulus_key = s.yarn.material == Material::zener ? "yarn.k1_pa" : "yarn.modulus_pa";
  // An auto end runs until the impact decides: a cap that holds fewer than 100 steps cannot.
  if (steps < 2 || (s.solver.end_time_auto && steps < 100))
    fail(modulus_key, "one time step (dt = alpha L0 / c = " + fmt3(s.solver.end_time_s / steps * 1e6) +
                          " us, wave speed c = " + fmt3(c) + " m/s) is longer than the run (" +
                          (s.solver.end_time_auto ? "solver.max_end_time_us = " : "solver.end_time_us = ") +
                          fmt3(s.solver.end_time_s * 1e6) + "); check the modulus, density and end time");
  if (steps > kMaxSteps)
    fail(modulus_key, "this scene would need about " + fmt3(steps) + " time steps (dt = alpha L0 / c with c = " +
                          fmt3(c) + " m/s) to reach solver.end_time_us; check the modulus, density and end time");
  if (steps > kManySteps)
    s.warnings.push_back("the run needs about " + fmt3(steps) + " time steps; expect it to take long");
  // The projectile should not cross the fabric in a step or two: contact is found from
  // positions at whole steps.
  const double dt_est = s.solver.dt_factor * std::min(L0, elem_len) / c;
  if (p.velocity_mps * dt_est > f.thickness_m)
    s.warnings.push_back("the projectile moves " + fmt3(p.velocity_mps * dt_est * 1e3) +
                         " mm per time step, more than the fabric thickness (" + fmt3(f.thickness_m * 1e3) +
                         " mm): contact may be missed; lower solver.dt_factor");
  // Values that look like they were given in another unit, and were not already refused.
  for (const auto& u : unit_slips()) {
    const KeyDef* d = find_def(u.key);
    if (!d || !d->get_number) continue;
    if (std::string h = units_hint(u.key, d->get_number(s) / d->scale); !h.empty())
      s.warnings.push_back(std::string(u.key) + " = " + fmt(d->get_number(s) / d->scale) +
                           (d->unit.empty() ? "" : " " + d->unit) + " is far outside the usual " + fmt(u.lo) + " .. " +
                           fmt(u.hi) + (d->unit.empty() ? "" : " " + d->unit) + h);
  }
}

namespace {
// A TOML basic string: quotes, backslashes and control characters escaped, so any name
// reads back as itself.
std::string toml_string(const std::string& v) {
  std::string o = "\"";
  for (unsigned char ch : v) {
    switch (ch) {
      case '"':
        o += "\\\"";
        break;
      case '\\':
        o += "\\\\";
        break;
      case '\n':
        o += "\\n";
        break;
      case '\t':
        o += "\\t";
        break;
      case '\r':
        o += "\\r";
        break;
      default:
        if (ch < 0x20 || ch == 0x7f) {
          char b[8];
          std::snprintf(b, sizeof b, "\\u%04X", ch);
          o += b;
        } else {
          o += char(ch);
        }
    }
  }
  return o + "\"";
}

// The shortest decimal (12 to 17 digits) of si / scale that reads back as the same SI
// value, so that the written scene.toml reproduces a run bit for bit.
std::string fmt_exact(double si, double scale) {
  std::string best;
  for (int digits = 12; digits <= 17; ++digits) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", digits, si / scale);
    best = b;
    if (std::strtod(b, nullptr) * scale == si) break;
  }
  return best;
}
}  // namespace

std::string scene_to_toml(const Scene& s) {
  std::ostringstream o;
  o << "# ravel scene\n";
  std::string section;
  for (const auto& d : defs()) {
    auto dot = d.key.find('.');
    std::string sec = dot == std::string::npos ? "" : d.key.substr(0, dot);
    std::string name = dot == std::string::npos ? d.key : d.key.substr(dot + 1);
    if (sec != section) {
      o << "\n[" << sec << "]\n";
      section = sec;
    }
    o << name << " = ";
    if (d.is_auto && d.is_auto(s)) {
      o << "\"auto\"";
    } else if (d.type == Type::text) {
      o << toml_string(d.get_text(s));
    } else if (d.type == Type::boolean) {
      o << (d.get_number(s) != 0 ? "true" : "false");
    } else if (d.type == Type::integer) {
      o << static_cast<long long>(d.get_number(s));
    } else {
      std::string v = fmt_exact(d.get_number(s), d.scale);
      if (v.find_first_of(".eE") == std::string::npos && v.find("inf") == std::string::npos) v += ".0";
      o << v;
    }
    o << "    # " << (d.unit.empty() ? "" : "[" + d.unit + "] ") << d.description << "\n";
  }
  return o.str();
}

std::string assets_dir() {
  if (const char* env = std::getenv("RAVEL_ASSETS")) return env;
  return RAVEL_ASSETS_DIR;
}

std::string default_scene_path() {
  return assets_dir() + "/scenes/twaron_ct716.toml";
}

}  // namespace ravel

// Scene: every input of a run, as read from a TOML file and `--set key=value` overrides.
//
// A Scene is plain data (SI units inside, the TOML keys carry their units in the name).
// load_scene() reads and validates it; every error names the key, the file and line
// where the value came from, and what is wrong (see SceneError).
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace ravel {

enum class Weave { plain, single_yarn };
enum class Material { zener, elastic };
enum class ContactModel { pin_jointed, sliding };
enum class SymmetryMode { automatic, full };
enum class Precision { double_precision, single_precision };
enum class ShapeKind { sphere, cylinder, cone };
// How a crossing's centre distance responds to its normal force (docs/MODEL.md §4).
enum class CrossingCompression { rigid, hyperbolic };
// How a clamp holds the yarns that end in it (docs/MODEL.md §7): rigid (the paper: no yarn
// leaves it) or slipping (it feeds yarn into the element that ends in it once that element's
// pull exceeds the clamp's grip: Coulomb friction of the clamp faces).
enum class ClampKind { rigid, slipping };

// Which fabric edges are clamped. "left"/"right" are the edges x = -W/2 and x = +W/2
// (they hold the weft yarns, which run along x); "bottom"/"top" are y = -L/2, +L/2
// (they hold the warp yarns, which run along y).
struct ClampedEdges {
  bool left = true, right = true, bottom = false, top = false;
  bool any() const { return left || right || bottom || top; }
  std::string to_string() const;
};

struct FabricParams {
  Weave weave = Weave::plain;
  double width_m = 0.120;          // along x
  double length_m = 0.120;         // along y
  double spacing_m = 0.844e-3;     // L0, horizontal node spacing
  double crossing_gap_m = 0.2e-3;  // L1, vertical distance of the two nodes at a crossing
  double node_mass_kg = 9.4e-8;    // m (paper: 9.4e-5 g)
  double thickness_m = 0.40e-3;    // fabric thickness; contact diameter D = thickness / 2
  ClampedEdges clamped;
  ClampKind clamp = ClampKind::rigid;  // the paper's rigid clamp, or one the yarns slip through
  // Slipping clamp: the pull along a real yarn at which it slides through the clamp faces
  // (Coulomb: 2 mu_c p w d for clamp pressure p on a yarn of width w over a depth d).
  double clamp_grip_n = 50.0;
  double clamp_depth_m = 25.0e-3;  // yarn held in the clamp: fed out past it, the yarn is free
  int yarns_per_element = 1;       // k real yarns lumped into one modelled yarn
  // Graded lumping (docs/MODEL.md §1): every real yarn within full_resolution_m of the
  // strike point is modelled; beyond it, one modelled yarn stands for far_yarns_per_element.
  int far_yarns_per_element = 1;        // 1 = no grading
  double full_resolution_m = 15.0e-3;   // half-width of the band modelled yarn by yarn
  double clamp_resolution_m = 15.0e-3;  // width of the band along each clamped edge modelled yarn by yarn
  // Transverse compression of the yarns at a crossing: rigid (the paper read literally:
  // centre distance D whatever the load) or hyperbolic, c(f) = c_min + (c0 - c_min) /
  // (1 + f / F_half), c0 the rest distance, f the crossing's normal force.
  CrossingCompression crossing_compression = CrossingCompression::hyperbolic;
  double flattened_gap_m = 0.10e-3;  // c_min: centre distance of two fully flattened yarns
  double compression_force_n = 0.5;  // F_half: normal force that closes half of c0 - c_pack (packing stage)
  // Two stages (docs/MODEL.md §4): the fibres of a yarn first pack (void closure, c0 -> c_pack,
  // at the force scale F_half), then the packed fibres themselves flatten (c_pack -> c_min, at
  // the force scale F_flat): c = c_min + (c_pack - c_min) / (1 + f / F_flat) + (c0 - c_pack) /
  // (1 + f / F_half). c_pack = c_min is the one-stage law.
  double packed_gap_m = 0.10e-3;   // c_pack: centre distance once the fibres are packed
  double flattening_force_n = 50;  // F_flat: force per crossing that closes half of c_pack - c_min
};

struct YarnParams {
  Material material = Material::zener;
  double modulus_pa = 7.28e10;   // elastic modulus E (material = elastic)
  double k1_pa = 7.28e10;        // Zener spring in series
  double k2_pa = 4.17e11;        // Zener spring of the Kelvin-Voigt unit
  double damping_pa_s = 6.26e8;  // Zener dashpot mu_d
  double density_kg_m3 = 1440.0;
  double area_m2 = 7.64e-8;
  double failure_strain = 0.052;  // <= 0 or >= 1e9 means unbreakable is not allowed; use `breakable`
  bool breakable = true;
  double friction = 0.2;           // yarn-yarn Coulomb coefficient mu
  double bending_fraction = 0.05;  // compression spring stiffness / element axial stiffness
  // Pin-jointed model: stiffness of the crimp stage (the yarn straightening its crimp before it
  // stretches) as a fraction of the yarn's modulus.
  double crimp_modulus_fraction = 0.05;
  double crimp_damping = 0.06;  // pin-jointed: damping of the crimp stage, fraction of critical (docs/MODEL.md §1)
};

struct ProjectileParams {
  ShapeKind shape = ShapeKind::sphere;
  double diameter_m = 12e-3;
  double length_m = 12e-3;  // cylinder length / cone height
  double mass_kg = 7e-3;
  double velocity_mps = 260.0;
  double friction = 0.27;   // projectile-yarn mu_p
  double offset_x_m = 0.0;  // strike point relative to the fabric centre
  double offset_y_m = 0.0;
  double obliquity_deg = 0.0;  // angle between the flight path and the fabric normal, in the x-z plane
};

struct SolverParams {
  ContactModel model = ContactModel::sliding;
  double dt_factor = 0.5;          // alpha of Eq 4
  int contact_iterations = 1;      // N of Eq 16-17
  double friction_penalty = 0.25;  // alpha_f of the stick penalty K = alpha_f m / dt^2 (Eq 12)
  bool split_penetration = true;   // resolve penetration left from earlier steps by moving nodes, not by velocity
  bool projectile_holds = true;    // nodes on the projectile do not yield into it under yarn contact
  SymmetryMode symmetry = SymmetryMode::automatic;
  Precision precision = Precision::double_precision;
  // Latest simulated time. auto: run until perforation or rebound, at most max_end_time_s
  // (then end_time_s is that cap); a number is a hard end.
  bool end_time_auto = true;
  double end_time_s = 5000e-6;
  double max_end_time_s = 5000e-6;
  int threads = 1;   // 0 = all cores
  bool simd = true;  // closest points in AVX2 lanes where available (bit-identical)
  // Damping of a slack element's snap taut, as a fraction of critical at the elements' highest
  // axial mode (docs/MODEL.md §3).
  double snap_damping = 0.01;
  double max_balance_error = 0.05;  // |ledger total - initial| / initial above this -> diverged
  double max_search_lost =
      0.01;  // nearest-pair search lost at more than this fraction of crossings in one step -> diverged
  // End a run as perforated once the projectile is passing through (docs/MODEL.md §8,
  // "Passing"): the limit searches' fast rule decide_passing; off for a plain run.
  bool decide_passing = false;
};

struct OutputParams {
  double history_interval_s = 0.25e-6;
  bool progress = true;
};

struct Scene {
  std::string name = "twaron_ct716";
  std::string source;  // file it came from ("" for built-in defaults)
  FabricParams fabric;
  YarnParams yarn;
  ProjectileParams projectile;
  SolverParams solver;
  OutputParams output;
  std::vector<std::string> warnings;  // physically questionable but allowed settings
  // Where each key's value came from (`scene.toml:12`, `--set`), for messages from checks
  // that run after parsing. Keys not listed kept their built-in default.
  std::map<std::string, std::string> origin;
};

// An error in a scene: the key (`projectile.mass_g`), where it came from
// (`scene.toml:12` or `--set`), and what is wrong.
class SceneError : public std::runtime_error {
 public:
  SceneError(std::string key, std::string where, std::string problem);
  const std::string& key() const { return key_; }
  const std::string& where() const { return where_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string key_, where_, problem_;
};

// Read a TOML scene file (or the built-in defaults when path is empty), apply the
// `key=value` overrides in order, validate. Throws SceneError.
Scene load_scene(const std::string& path, const std::vector<std::string>& overrides = {});

// Parse TOML text directly (used by tests, the app's editor and the fuzzer).
Scene parse_scene(const std::string& toml_text, const std::string& source_name,
                  const std::vector<std::string>& overrides = {});

// Check ranges and consistency; throws SceneError for the first hard error and
// appends soft problems to scene.warnings.
void validate_scene(Scene& scene);

// The scene as TOML text, with every key, so that parse_scene(to_toml(s)) == s.
std::string scene_to_toml(const Scene& scene);

// Every key the scene understands, with its unit and a one-line description.
struct SceneKeyInfo {
  std::string key, unit, description;
  std::string default_value;  // what the key is when a scene file leaves it out, as TOML
  std::string range;          // allowed values: "[0, 1]", "> 0", "a | b", "" for any
};
const std::vector<SceneKeyInfo>& scene_keys();

// The folder of shipped assets (scenes), and the default scene file.
std::string assets_dir();
std::string default_scene_path();

const char* to_string(ContactModel m);
const char* to_string(Material m);
const char* to_string(Weave w);
const char* to_string(ShapeKind s);
const char* to_string(CrossingCompression c);
const char* to_string(ClampKind c);

}  // namespace ravel

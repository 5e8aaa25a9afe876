// SolverT<Real>: the solver of solver.h in single or double precision, shared by the stage
// files of this folder (one per stage of step(), in the order step() runs them):
//
//   internal_forces.cpp     element strain -> stress (Zener / elastic, crimp stage), failure,
//                           bending springs, nodal forces
//   ledger.cpp              the energy book: the ledger row at t - dt/2, the kinetic energy
//                           and the corrections' work at the end of the step
//   integrate.cpp           Eq 1-2, the free update
//   projectile_contact.cpp  Eq 18-22, and the yarn contact's push on held nodes passed on
//   yarn_contact.cpp        Eq 5-17: crossing tracking, closest points, normal correction with
//                           the compression law, stick/slip friction
//   faults.cpp              divergence: the checks and the message
//   setup.cpp               construction from the model, make_solver
//   state.cpp               the state hash
//   simd/                   the lane kernels (AVX2 / AVX-512) the stages call
//
// Private to core/: the rest of ravel sees the Solver interface of solver.h only.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "geometry.h"
#include "material.h"
#include "solver.h"
#include "solver/simd/contact_lanes.h"
#include "solver/simd/element_lanes.h"
#include "solver/state.h"

#ifdef _OPENMP
#include <omp.h>
#endif

// The per-crossing helpers the stages call in their hot loops are inlined into them, as the
// compiler did when the whole solver was one class in one file (left to its heuristics, the
// out-of-line definitions made the default scene's step 3.5 % slower).
#define RAVEL_INLINE [[gnu::always_inline]] inline

namespace ravel::detail {

template <class Real>
class SolverT final : public Solver {
 public:
  using V3 = Eigen::Matrix<Real, 3, 1>;

  SolverT(const Model& m, int threads);

  void set_threads(int n) override {
#ifdef _OPENMP
    threads_ = n <= 0 ? omp_get_num_procs() : n;
#else
    threads_ = 1;
    (void)n;
#endif
  }
  void set_simd(bool on) override {
    simd_ = on && lanes_possible();
  }
  bool simd_active() const override {
    return lanes_on();
  }

  void step() override {
    if (!run_.divergence.empty()) return;
    internal_forces();                              // Eq 3, 23: element stress from strain; bending; failure
    close_ledger_row();                             // ledger at t - dt/2
    integrate();                                    // Eq 1-2
    projectile_contact();                           // Eq 18-22
    if (!model_.crossings.empty()) yarn_contact();  // Eq 5-17
    release_held();                                 // the yarn contact's push on held nodes -> projectile
    if (!model_.crossings.empty() && run_.steps % kPenetrationCheckEvery == 0) residual_penetration();
    finish_step();
    if (run_.steps % kProjectileCheckEvery == 0) check_projectile();
  }

  Vec3d projectile_position() const override {
    return s_.xp.template cast<double>();
  }
  Vec3d projectile_velocity() const override {
    return s_.vp.template cast<double>();
  }
  Vec3d position(int i) const override {
    return s_.x[i].template cast<double>();
  }
  Vec3d velocity(int i) const override {
    return s_.v[i].template cast<double>();
  }
  void set_velocity(int i, const Vec3d& v) override {
    s_.v[i] = v.cast<Real>();
  }
  void set_position(int i, const Vec3d& x) override {
    s_.x[i] = x.cast<Real>();
  }
  void set_projectile_velocity(const Vec3d& v) override {
    s_.vp = v.cast<Real>();
    s_.book.ke_half = fabric_ke() + 0.5 * model_.projectile_mass * double(s_.vp.squaredNorm());
  }
  void set_projectile_position(const Vec3d& x) override {
    s_.xp = x.cast<Real>();
  }
  void set_external_force(int node, const Vec3d& f) override {
    for (auto& e : s_.f_ext)
      if (e.first == node) {
        e.second = f.cast<Real>();
        return;
      }
    s_.f_ext.push_back({node, f.cast<Real>()});
  }
  double strain(int e) const override {
    return double(s_.strain[e]);
  }
  double stress(int e) const override {
    return double(s_.stress[e]);
  }
  bool broken(int e) const override {
    return s_.broken_flag[e] != 0;
  }
  bool crossing_active(int c) const override {
    return s_.cr_active[c] != 0;
  }
  bool crossing_sliding(int c) const override {
    return s_.cr_sliding[c] != 0;
  }
  double crossing_normal_force(int c) const override {
    return s_.cr_fn[c];
  }
  double crossing_friction_force(int c) const override {
    return s_.cr_ft[c];
  }
  double crossing_slip_rate(int c) const override {
    return s_.cr_slip[c];
  }
  double crossing_gap(int c) const override {
    return s_.cr_gap[c];
  }
  int crossing_warp_node(int c) const override {
    return s_.cr_kw[c];
  }
  int crossing_weft_node(int c) const override {
    return s_.cr_kf[c];
  }

 protected:
  void save_state(StateWriter& w) const override {
    const_cast<SolverT*>(this)->state_io(w);
  }
  void load_state(StateReader& r) override {
    state_io(r);
  }

  // The whole dynamic state: the base class's RunState, then State (core/solver/state.h).
  template <class Ar>
  void state_io(Ar& ar) {
    run_.io(ar);
    s_.io(ar);
  }

  void hash_into(std::uint64_t& h) const override;

 private:
  // ---------------------------------------------------------------- setup.cpp
  void build_incidence();

  // ------------------------------------------------------ internal_forces.cpp
  bool element_one(int e, bool zener, double E, double fail, bool breakable, double& stored, double& diss,
                   double& released, double& max_strain, double& damp);

  // The pin-jointed crimp stage (Model::crimp_strain): apparent strain e (against the node
  // spacing L0) -> the yarn law's strain g(e) = r e + (1 - r) p(e - e_c) and g'(e), with
  // p(x) = (x + e_c)^2 / (4 e_c) across [-e_c, e_c], x above, 0 below: a toe whose stiffness
  // rises linearly from r times the modulus at e = 0 to the full modulus at e = 2 e_c, after
  // which the yarn stretches with g = e - (1 - r) e_c (the toe's own force, r E e_c, stays: it is
  // what holds the crimp out). A force-free slack switched elements between slack and taut from
  // step to step; a longer, softer toe let the whole ply deflect before the crimp was out and
  // tore it off the clamps (docs/MODEL.md §1). `e` is returned as the yarn's own strain
  // (1 + e) / (1 + e_c) - 1, which failure and the outputs use: a yarn breaks at its own stretch.
  void crimp_stage(Real& e, Real& mat, Real& dg) const {
    const double ec = model_.crimp_strain, r = model_.crimp_fraction, w = model_.crimp_width;
    const double x = double(e) - ec;
    double p = 0, dp = 0;
    if (x >= w)
      p = x, dp = 1;
    else if (x > -w)
      p = (x + w) * (x + w) / (4 * w), dp = (x + w) / (2 * w);
    mat = Real(r * double(e) + (1 - r) * p);
    dg = Real(r + (1 - r) * dp);
    e = Real((1 + double(e)) / (1 + ec) - 1);
  }

  void internal_forces();

  // --------------------------------------------------------------- ledger.cpp
  void close_ledger_row();
  static constexpr long kBalanceWindow = 64;  // steps per window of the drift/instability test

  // ------------------------------------------------------------ integrate.cpp
  void integrate();

  // Zero the components of a node's velocity / displacement change along its fixed axes
  // (clamps, symmetry planes).
  static void zero_fixed(V3& v, std::uint8_t fx) {
    if (fx & fix_x) v.x() = 0;
    if (fx & fix_y) v.y() = 0;
    if (fx & fix_z) v.z() = 0;
  }

  // ------------------------------------------ yarn_contact.cpp: yarn contact (Eq 5-17)
  int ynode(int yarn, int k) const {
    return model_.yarn_node(yarn, k);
  }
  bool seg_ok(int yarn, int s) const {
    return s >= 0 && s + 1 < model_.yarn_size(yarn) && !s_.broken_flag[model_.yarn_elem_offset[yarn] + s];
  }
  Real seg_len(int yarn, int s) const {
    return (s_.x[ynode(yarn, s + 1)] - s_.x[ynode(yarn, s)]).norm();
  }

  // int(std::floor(u)) for a material coordinate. Those are >= 0 but for rounding, and the
  // truncating conversion is then the floor in one instruction (std::floor is a libm-like
  // sequence on the baseline x86-64 without SSE4.1's roundsd).
  static int floor_int(double u) {
    return u >= 0 ? int(u) : int(std::floor(u));
  }
  // Lengths of two consecutive segments of a yarn, first and first + 1, known already (the
  // lanes measured them); other segments are measured when asked for.
  struct KnownLengths {
    int first = -(1 << 30);  // none
    Real len[2];
  };
  Real seg_len(int yarn, int s, const KnownLengths& known) const {
    const unsigned i = unsigned(s - known.first);
    return i < 2 ? known.len[i] : seg_len(yarn, s);
  }

  Real arc_between(int yarn, double u0, double u1, const KnownLengths& known = {}) const;
  double advance(int yarn, double u, double arc, const KnownLengths& known = {}) const;

  // The nodes around a crossing's tracked pair, loaded once per pass: warp nodes kw-1..kw+1
  // and weft nodes kf-1..kf+1 (id -1 past a yarn's end), their positions and whether the two
  // segments of each yarn next to the tracked node are intact. Tracking, the closest points,
  // the side test and the chord coordinates all work on this window.
  struct Window {
    int kw, kf;  // set by load_window
    int wnode[3], fnode[3];
    V3 xw[3], xf[3];
    bool wseg[2], fseg[2];  // warp segments kw-1, kw; weft segments kf-1, kf intact
  };
  using WindowIds = detail::WindowIds;
  WindowIds window_ids(const Crossing& cr, int kw, int kf) const;
  void load_window(const WindowIds& id, Window& w) const;
  void load_window(int c, Window& w);
  void load_window(const Crossing& cr, int kw, int kf, Window& w) const;

  bool track(int c, Window& w, bool loaded = false);

  void release(int c, std::uint8_t why);

  // The contact between two crossing yarns: closest points of the 2 x 2 adjoining
  // segment pairs (Eq 5-8). The zig-zag's kinks make pairs tie for the smallest |d| (at rest
  // all four do); pairs within kTieBand * D of the closest share the contact, so the
  // correction is continuous in the state and a mirror-symmetric state gets a
  // mirror-symmetric correction (see docs/MODEL.md).
  static constexpr double kTieBand = 0.02;
  // The share of a compressible crossing's closure left from before the step (below its
  // flattened distance, or beyond the law's) that one step's shift removes. A crossing
  // alone would take all of it; under the Jacobi sweep the shifts of neighbouring crossings
  // that share nodes add up, and a broken end sliding through compressed crossings then set
  // off a cascade of ever larger shifts (a 70 m/s default-scene run: shifts of 20-90 um per
  // step, elements stretched past failure in one step, and a diverged energy balance at
  // 0.5 ms with the full shift; 0.1 % balance error with half). Rigid crossings keep the
  // paper's full correction.
  static constexpr double kCompressedShift = 0.5;
  // ... and at most this share of D per step. A shift's work against the yarn forces is booked
  // by the trapezoid rule, half with the force of the next step, after that step's motion too;
  // the error grows with shift times motion, and shifts of 30-45 um per step at free edges
  // where yarn ends whip at 200 m/s created 20 % of the impact energy over 1.4-3.6 ms of
  // slowly caught low-friction runs near the ballistic limit. A closure left over is met
  // again the next step.
  static constexpr double kMaxCompressedShift = 0.02;
  // The most closure below the flattened distance c_min the cap may leave, as a share of c_min.
  static constexpr double kFloorLeft = 0.5;
  static Real compressed_shift(Real closure, Real D) {
    return std::min(Real(kCompressedShift) * closure, Real(kMaxCompressedShift) * D);
  }
  // The least share of a crossing's mobility the projectile's hold may leave (see pass_normal).
  static constexpr double kMinHeldMobility = 0.25;
  // No member initialisers: the batches' arrays of these are filled, not cleared first
  // (closest starts from a zeroed one, the lanes set every field).
  struct ContactGeom {
    bool ok;
    int sw, sf;  // the first closest pair (for the end-of-yarn tests)
    Real a, b;
    V3 d;        // contact vector warp -> weft (mean over tied pairs)
    Real dist;   // smallest |d|
    Real ww[3];  // weights on warp nodes kw-1, kw, kw+1
    Real wf[3];  // weights on weft nodes kf-1, kf, kf+1
    int lane;    // computed in this lane of the batch's lanes::ClosestBatch, which then has the
                 // rest of the window's geometry too; -1: computed alone
    bool moved;  // (lanes) another node pair of the window is nearer than the tracked one
  };

  ContactGeom closest(const Crossing& cr, const Window& w) const;

  // Cross product of the first closest pair's warp and weft segments; times the crossing's
  // fixed sign it is the side test's normal n (SPEC §4), unnormalised.
  static V3 pair_cross(const Window& w, const ContactGeom& g) {
    const V3 tw = w.xw[g.sw - w.kw + 2] - w.xw[g.sw - w.kw + 1];
    const V3 tf = w.xf[g.sf - w.kf + 2] - w.xf[g.sf - w.kf + 1];
    return tw.cross(tf);
  }

  bool slipped_off(int yarn, int seg, Real frac, const V3& toward_partner) const;

  double chord_coord(int yarn, int k, const V3* xs, const bool* seg, const V3& p, V3& tangent) const;
  void coord_nodes(int yarn, double u, int& n0, int& n1, Real& frac) const;

  // One crossing's corrections for one pass, computed from the same state for every
  // crossing (Jacobi) and applied afterwards in a fixed order: the result does not depend
  // on the order crossings are visited in, nor on the number of threads.
  struct CrossingImpulse {
    int node[6];   // warp kw-1..kw+1, weft kf-1..kf+1 (-1: none)
    Real w[6];     // signed weights: -warp, +weft
    V3 P;          // normal impulse on the weft contact point (Eq 9-11)
    V3 S;          // position shift (mass-weighted, like P) of penetration left from before the step
    int fnode[4];  // friction: warp pair, weft pair
    Real fw[4];
    V3 F;  // friction impulse on the weft contact point (Eq 15)
    V3 C;  // compression: the impulse of the crossing's transverse-compression law (same weights as P)
    bool has_n, has_f, has_s, has_c;
    bool any_held;  // a window node is held by the projectile (set by pass_normal)
    bool hold;      // nodes the projectile holds do not yield into it (release_held)
  };

  // Inside a parallel region: this thread's share [lo, hi) of n items (contiguous, in
  // thread order) and its number t.
  static void my_share(int n, int& lo, int& hi, int& t) {
#ifdef _OPENMP
    t = omp_get_thread_num();
    const int T = omp_get_num_threads();
#else
    t = 0;
    const int T = 1;
#endif
    lo = int(long(n) * t / T);
    hi = int(long(n) * (t + 1) / T);
  }

  void yarn_contact();

  // Gather one crossing's corrections of a pass for the nodes in [lo, hi): per node sums,
  // applied once per node by finish_pass; nodes the projectile holds take each correction
  // separately, as the hold projects out the part pushing into the projectile.
  void gather(const CrossingImpulse& r, int lo, int hi);

  void finish_pass(int lo, int hi);

  void apply_impulse(int i, V3 P, std::vector<V3>* acc, bool hold, std::vector<V3>* part);

  void shift_node(int i, const V3& S, bool hold);

  // Crossings [c0, c1) (at most kBatch) in one pass: tracking of each, then the closest
  // points of those whose four segments are intact together in lanes (when on and the
  // processor has them; the same numbers bit for bit), then the rest of each.
  static constexpr int kBatch = lanes::kWidth;
  bool lanes_on() const {
    return simd_;  // set_simd: asked for, double precision, and the processor has the lanes
  }
  void crossing_batch(int c0, int c1, Real alpha, bool first, bool last, CrossingImpulse* out);

  // Whether the lanes take a window: all four segments next to the tracked pair intact.
  bool lane_window(const Window& w) const {
    return lanes_on() && w.wseg[0] && w.wseg[1] && w.fseg[0] && w.fseg[1];
  }
  void closest_batch(int c0, int c1, const bool* on, const Window* w, ContactGeom* g, lanes::ClosestBatch& lb) const;

  bool pass_normal(int c, Real alpha, bool last, const Window& w, const ContactGeom& g, const lanes::ClosestBatch& lb,
                   CrossingImpulse& r);

  void compress(int c, Real alpha, bool last, Real s_p, Real span, Real winv, Real P, Real approach, const V3& u,
                CrossingImpulse& r);

  // Friction (Eq 12-15), per yarn, against the stuck material points. The contact's
  // material coordinate on each yarn is the partner's contact point projected on this
  // yarn's chord through its tracked node: continuous in time, unlike the raw closest
  // point, which jumps between the equivalent segment pairs of the zig-zag.
  struct FrictionSetup {
    double cw, cf;        // material coordinates of the contact on the warp and the weft
    V3 Tw, Tf;            // unit chord tangents
    double fwinv;         // inverse effective mass of the contact points' relative motion
    KnownLengths lw, lf;  // the window's segment lengths, when the lanes measured them
  };
  void friction_setup(int c, const Window& w, const ContactGeom& g, const lanes::ClosestBatch& lb, CrossingImpulse& r,
                      FrictionSetup& s);

  void pass_friction(int c, Real alpha, bool last, const FrictionSetup& s, CrossingImpulse& r);

  // --------------------------------------------------- projectile_contact.cpp
  void projectile_contact();
  void release_held();

  // (yarn_contact.cpp) The interpenetration left at the end of a step (after every correction),
  // sampled every kPenetrationCheckEvery steps: what the contact algorithm failed to resolve.
  static constexpr int kPenetrationCheckEvery = 8;
  void residual_penetration();

  // --------------------------------------------------------------- ledger.cpp
  double fabric_ke() const;
  double shift_energy();
  double element_energy_at(int e, Real len) const;
  // A bending spring's energy with node positions from pos (internal_forces' law; 0 when
  // either element is broken).
  template <class Pos>
  double bend_energy_at(int sp, Pos&& pos) const {
    const int e1 = model_.bend_e1[sp], e2 = model_.bend_e2[sp];
    if (s_.broken_flag[e1] || s_.broken_flag[e2]) return 0;
    const double k = model_.bend_k[sp], r = model_.bend_rest[sp];
    if (const int ax = model_.bend_mirror[sp]; ax >= 0) {
      const double mc = 0.5 * double(pos(model_.elem_a[e1])[ax] + pos(model_.elem_b[e1])[ax]);
      const double comp = r - 2 * std::abs(mc);
      return comp > 0 ? 0.25 * k * comp * comp : 0.0;
    }
    const V3 m1 = Real(0.5) * (pos(model_.elem_a[e1]) + pos(model_.elem_b[e1]));
    const V3 m2 = Real(0.5) * (pos(model_.elem_a[e2]) + pos(model_.elem_b[e2]));
    const double sl = double((m2 - m1).norm());
    if (sl >= r) return 0;
    return sl >= 0.5 * r ? 0.5 * k * (r - sl) * (r - sl) : 0.25 * k * r * r - 0.5 * k * sl * sl;
  }

  void finish_step();

  // faults.cpp: the checks that stop a run (Solver::fault records it).
  void check_balance(double total);
  void check_positions(double max_r2);
  static constexpr int kProjectileCheckEvery = 16;
  void check_projectile();

 private:
  // --- The run's dynamic state (state.h): plain data, copied, hashed and written as one.
  State<Real> s_;

  // --- What the model and the options determine (rebuilt by the constructor, not written).
  int threads_ = 1;
  // Lanes in use (contact_lanes.h, element_lanes.h): asked for, double precision, and the
  // processor has them.
  static bool lanes_possible() {
    return std::is_same_v<Real, double> && lanes::available();
  }
  bool simd_ = lanes_possible();
  ZenerStepper zener_;
  bool compressible_ = false;
  // Node -> (element, sign) and node -> (bending spring, weight), in CSR form (build_incidence).
  std::vector<int> inc_e_off_, inc_b_off_;
  std::vector<std::pair<int, Real>> inc_e_, inc_b_;
  double escape_radius2_ = 1;
  // beta E_inst of the element damping (model's element_damping_beta times the instantaneous modulus).
  double damping_k_ = model_.element_damping_beta * model_.modulus_inst;
  double crimp_damping_k_ = model_.crimp_damping_beta * model_.modulus_inst;  // the same for yarn.crimp_damping

  // --- Per-step scratch: what a stage needs within a step and forgets.
  std::vector<int> near_;                    // projectile_contact: nodes in its bounding box
  std::vector<std::vector<int>> near_part_;  // the same, per thread
  std::vector<int> rec_first_, rec_last_;    // (threads) node bounds of the pass's records, running
  std::vector<CrossingImpulse> impulses_;

  using LastPair = detail::LastPair<Real>;
  V3 pair_offset(int c, int kw, int kf) const {
    const Crossing& cr = model_.crossings[c];
    const int nw = model_.yarn_size(cr.warp_yarn), nf = model_.yarn_size(cr.weft_yarn);
    const int iw = model_.yarn_node(cr.warp_yarn, std::clamp(kw, 0, nw - 1));
    const int jf = model_.yarn_node(cr.weft_yarn, std::clamp(kf, 0, nf - 1));
    return s_.x[jf] - s_.x[iw];
  }
  enum : std::uint8_t { ev_skip = 1, ev_ravel = 2, ev_pass = 4, ev_lost = 8, ev_separated = 16 };
};

}  // namespace ravel::detail

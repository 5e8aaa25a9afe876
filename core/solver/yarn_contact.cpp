// Stage yarn_contact (Eq 5-17): crossing tracking, closest points, the normal correction with
// the compression law, stick/slip friction.
#include "solver/hold.h"
#include "solver/stage.h"

namespace ravel::detail {
namespace {

// The stage's inputs, bound for its helpers.
template <class Real>
struct YarnContact {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  using LastPair = detail::LastPair<Real>;
  using PassSum = typename State<Real>::PassSum;
  using Corrections = typename State<Real>::Corrections;
  const Model& model_;
  State<Real>& s_;
  RunState& run_;
  Context<Real>& ctx_;

  int ynode(int yarn, int k) const { return model_.yarn_node(yarn, k); }
  bool seg_ok(int yarn, int s) const {
    return s >= 0 && s + 1 < model_.yarn_size(yarn) && !s_.broken_flag[model_.yarn_elem_offset[yarn] + s];
  }
  Real seg_len(int yarn, int s) const { return (s_.x[ynode(yarn, s + 1)] - s_.x[ynode(yarn, s)]).norm(); }

  // int(std::floor(u)) for a material coordinate. Those are >= 0 but for rounding, and the
  // truncating conversion is then the floor in one instruction (std::floor is a libm-like
  // sequence on the baseline x86-64 without SSE4.1's roundsd).
  static int floor_int(double u) { return u >= 0 ? int(u) : int(std::floor(u)); }
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
  // The pace holds below the flattened distance c_min too. A shift is a position change
  // without a force: the yarn elements of a shifted node are stretched without resisting.
  // Removing in one step all but half of c_min of such a closure (the rule until 2026-12-05)
  // moved nodes by 50-100 um, mostly at crossings passed through or re-paired in the bunched
  // weave near the projectile, and every yarn that broke after the first clamp-line breaks of
  // a 70 m/s default-scene run was an element near zero strain stretched to 6-9 % by such a
  // shift (the pole warps that held the projectile among them: at 78 m/s the run perforated
  // at 3.5 ms instead of rebounding). Paced, the yarns' own forces answer between steps; a
  // crossing the pace cannot keep up with passes through and is released (counted).
  static constexpr double kMaxCompressedShift = 0.02;
  static Real compressed_shift(Real closure, Real D) {
    return std::min(Real(kCompressedShift) * closure, Real(kMaxCompressedShift) * D);
  }
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

  using CrossingImpulse = detail::CrossingImpulse<Real>;

  void run();
  void residual_penetration();
  // The next step's split of the nb crossing batches among the threads (Context::batch_bound).
  void rebalance_batches(int nb);

  // After the last pass: the yarns' relative move at crossing c, its slip bound and its
  // share of the step's sums (into tally).
  void moved_since_last(int c, ContactTally& tally);
  // Gather one crossing's corrections of a pass for the nodes in [lo, hi): per node sums,
  // applied once per node by finish_pass; nodes the projectile holds take each correction
  // separately, as the hold projects out the part pushing into the projectile.
  void gather(const CrossingImpulse& r, int lo, int hi);

  struct NodeShare {
    V3 dvn, dvf, dx, dvc;  // velocity changes of the normal, friction and compression parts; shift
  };
  NodeShare take_share(int i);
  void finish_pass(int lo, int hi);
  // The last pass's: also the ledger's sums over the nodes (Book::finish_step) into `book`,
  // and the shifted nodes into `shifted`.
  void finish_last_pass(int lo, int hi, NodeBook& book, std::vector<int>& shifted);

  void apply_impulse(int i, V3 P, V3 Corrections::*acc, bool hold, std::vector<V3>* part);

  void shift_node(int i, const V3& S, bool hold);

  // Crossings [c0, c1) (at most kBatch) in one pass: tracking of each, then the closest
  // points of those whose four segments are intact together in lanes (when on and the
  // processor has them; the same numbers bit for bit), then the rest of each.
  static constexpr int kBatch = lanes::kWidth;
  void crossing_batch(int c0, int c1, Real alpha, bool first, bool last, CrossingImpulse* out);

  // Whether the lanes take a window: all four segments next to the tracked pair intact.
  bool lane_window(const Window& w) const { return ctx_.simd && w.wseg[0] && w.wseg[1] && w.fseg[0] && w.fseg[1]; }
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

  void pass_friction(int c, const FrictionSetup& s, CrossingImpulse& r);

  enum : std::uint8_t { ev_skip = 1, ev_ravel = 2, ev_pass = 4, ev_lost = 8, ev_separated = 16 };
};

}  // namespace

// Arc length along a yarn from material coordinate u0 to u1 (coordinate = segment + fraction).
template <class Real>
inline auto YarnContact<Real>::arc_between(int yarn, double u0, double u1, const KnownLengths& known) const -> Real {
  // Both ends on one segment of known length (the usual stuck contact): (u1 - u0) times
  // that length, which is what the general walk below gives then too.
  if (const int a = floor_int(u0); unsigned(a - known.first) < 2u && a == floor_int(u1))
    return Real(u1 - u0) * known.len[a - known.first];
  auto seg_len = [&](int, int s) { return this->seg_len(yarn, s, known); };
  const int n = model_.yarn_size(yarn);
  double sign = 1;
  if (u1 < u0) std::swap(u0, u1), sign = -1;
  int s0 = std::min(floor_int(u0), n - 2), s1 = std::min(floor_int(u1), n - 2);
  if (s0 == s1) return Real(sign * (u1 - u0)) * seg_len(yarn, s0);
  Real acc = Real(s0 + 1 - u0) * seg_len(yarn, s0);
  for (int s = s0 + 1; s < s1; ++s) acc += seg_len(yarn, s);
  acc += Real(u1 - s1) * seg_len(yarn, s1);
  return Real(sign) * acc;
}

// Material coordinate reached by moving an arc length `arc` (signed) from u.
template <class Real>
inline double YarnContact<Real>::advance(int yarn, double u, double arc, const KnownLengths& known) const {
  auto seg_len = [&](int, int s) { return this->seg_len(yarn, s, known); };
  const int n = model_.yarn_size(yarn);
  int s = std::min(floor_int(u), n - 2);
  double frac = u - s;
  while (true) {
    const double L = double(seg_len(yarn, s));
    if (L <= 0) return u;
    const double room = arc >= 0 ? (1 - frac) * L : frac * L;
    if (std::abs(arc) <= room || (arc >= 0 ? s == n - 2 : s == 0)) {
      double nf = frac + arc / L;
      return s + std::clamp(nf, 0.0, 1.0);
    }
    arc += arc >= 0 ? -room : room;
    if (arc >= 0)
      ++s, frac = 0;
    else
      --s, frac = 1;
  }
}

template <class Real>
RAVEL_INLINE auto YarnContact<Real>::window_ids(const Crossing& cr, int kw, int kf) const -> WindowIds {
  WindowIds id;
  id.kw = kw;
  id.kf = kf;
  const int* wn = &model_.yarn_nodes[model_.yarn_offset[cr.warp_yarn]];  // node ids by position along the yarn
  const int* fn = &model_.yarn_nodes[model_.yarn_offset[cr.weft_yarn]];
  const int nw = model_.yarn_size(cr.warp_yarn), nf = model_.yarn_size(cr.weft_yarn);
  for (int k = 0; k < 3; ++k) {
    const int iw = kw - 1 + k, jf = kf - 1 + k;
    id.node[k] = (iw >= 0 && iw < nw) ? wn[iw] : -1;
    id.node[3 + k] = (jf >= 0 && jf < nf) ? fn[jf] : -1;
  }
  id.wseg0 = model_.yarn_elem_offset[cr.warp_yarn] + kw - 1;
  id.fseg0 = model_.yarn_elem_offset[cr.weft_yarn] + kf - 1;
  id.exists = 0;
  for (int k = 0; k < 2; ++k) {
    const int sw = kw - 1 + k, sf = kf - 1 + k;
    if (sw >= 0 && sw + 1 < nw) id.exists |= std::uint8_t(1 << k);
    if (sf >= 0 && sf + 1 < nf) id.exists |= std::uint8_t(4 << k);
  }
  return id;
}

// The nodes' positions and whether the four segments next to the pair are intact.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::load_window(const WindowIds& id, Window& w) const {
  w.kw = id.kw;
  w.kf = id.kf;
  for (int k = 0; k < 3; ++k) {
    w.wnode[k] = id.node[k];
    w.fnode[k] = id.node[3 + k];
    if (w.wnode[k] >= 0) w.xw[k] = s_.x[w.wnode[k]];
    if (w.fnode[k] >= 0) w.xf[k] = s_.x[w.fnode[k]];
  }
  for (int k = 0; k < 2; ++k) {
    w.wseg[k] = (id.exists >> k & 1) && !s_.broken_flag[id.wseg0 + k];
    w.fseg[k] = (id.exists >> (2 + k) & 1) && !s_.broken_flag[id.fseg0 + k];
  }
}

// The window of crossing c around its tracked pair.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::load_window(int c, Window& w) {
  WindowIds& id = s_.cr[c].win;
  if (id.kw != s_.cr[c].kw || id.kf != s_.cr[c].kf) id = window_ids(model_.crossings[c], s_.cr[c].kw, s_.cr[c].kf);
  load_window(id, w);
}

template <class Real>
RAVEL_INLINE void YarnContact<Real>::load_window(const Crossing& cr, int kw, int kf, Window& w) const {
  load_window(window_ids(cr, kw, kf), w);
}

// Nearest node pair tracking: search the 3 x 3 neighbours (paper Fig. 2). A move at the
// edge of the window is searched once more; moving again means the yarns slid more than
// one node in one step, which the method assumes never happens: reported, not hidden.
// Returns true in that case; `w` is left loaded around the tracked pair.
template <class Real>
inline bool YarnContact<Real>::track(int c, Window& w, bool loaded) {
  const Crossing& cr = model_.crossings[c];
  bool skipped = false;
  if (!loaded) load_window(c, w);
  for (int round = 0; round < 4; ++round) {
    int bw = 1, bf = 1;
    Real best = (w.xf[1] - w.xw[1]).squaredNorm();
    for (int iw = 0; iw < 3; ++iw) {
      if (w.wnode[iw] < 0) continue;
      for (int jf = 0; jf < 3; ++jf) {
        if (w.fnode[jf] < 0 || (iw == 1 && jf == 1)) continue;
        const Real d2 = (w.xf[jf] - w.xw[iw]).squaredNorm();
        if (d2 < best) best = d2, bw = iw, bf = jf;
      }
    }
    if (bw == 1 && bf == 1) break;
    s_.cr[c].kw += bw - 1;
    s_.cr[c].kf += bf - 1;
    if (round >= 1) skipped = true;
    load_window(cr, s_.cr[c].kw, s_.cr[c].kf, w);
  }
  return skipped;
}

template <class Real>
RAVEL_INLINE void YarnContact<Real>::release(int c, std::uint8_t why) {
  s_.cr[c].active = 0;
  s_.cr[c].stick_e = 0;  // the penalty spring lets go (its energy then shows as friction work)
  s_.cr[c].fn = s_.cr[c].ft = s_.cr[c].slip = 0;
  s_.cr[c].sliding = 0;
  s_.cr[c].event |= why;
}

template <class Real>
inline auto YarnContact<Real>::closest(const Crossing& cr, const Window& w) const -> ContactGeom {
  ContactGeom g{};
  g.d.setZero();
  g.lane = -1;
  g.moved = false;
  const int kw = w.kw, kf = w.kf;
  // The up to 2 segments of each yarn next to the tracked node: start point, direction,
  // squared length (done once, each segment serves two pairs).
  V3 p0[2], d1[2], q0[2], d2[2];
  Real aa[2], ee[2];
  int sws[2], sfs[2], nw = 0, nf = 0;
  for (int k = 0; k < 2; ++k) {
    if (!w.wseg[k]) continue;
    p0[nw] = w.xw[k];
    d1[nw] = w.xw[k + 1] - p0[nw];
    aa[nw] = d1[nw].squaredNorm();
    sws[nw++] = kw - 1 + k;
  }
  for (int k = 0; k < 2; ++k) {
    if (!w.fseg[k]) continue;
    q0[nf] = w.xf[k];
    d2[nf] = w.xf[k + 1] - q0[nf];
    ee[nf] = d2[nf].squaredNorm();
    sfs[nf++] = kf - 1 + k;
  }
  if (nw == 0 || nf == 0) return g;
  // The first closest pair is chosen below; this default only stands when no distance
  // compares (a NaN state, which the ledger check then stops), and keeps g.sw / g.sf
  // inside the window.
  g.sw = sws[0];
  g.sf = sfs[0];
  struct Cand {
    int iw, jf;
    Real a, b, dist2;
    V3 d;
  } cand[4];
  int nc = 0;
  Real best2 = Real(1e30);
  for (int i = 0; i < nw; ++i)
    for (int j = 0; j < nf; ++j) {
      // Segment-segment closest points (Eq 8, clamped; Ericson 5.1.9), inlined with the
      // segments' squared lengths reused.
      const V3 r = p0[i] - q0[j];
      const Real A = aa[i], E = ee[j], F = d2[j].dot(r);
      const Real C = d1[i].dot(r), B = d1[i].dot(d2[j]);
      const Real denom = A * E - B * B;
      Real sa = denom > Real(1e-12) * A * E ? std::clamp((B * F - C * E) / denom, Real(0), Real(1)) : Real(0);
      Real tb = (B * sa + F) / E;
      if (tb < Real(0)) {
        tb = 0;
        sa = std::clamp(-C / A, Real(0), Real(1));
      } else if (tb > Real(1)) {
        tb = 1;
        sa = std::clamp((B - C) / A, Real(0), Real(1));
      }
      Cand& q = cand[nc++];
      q.iw = i;
      q.jf = j;
      q.a = sa;
      q.b = tb;
      q.d = (q0[j] + tb * d2[j]) - (p0[i] + sa * d1[i]);
      q.dist2 = q.d.squaredNorm();
      best2 = std::min(best2, q.dist2);
    }
  // Pairs within kTieBand * D of the closest share the contact, with weights falling
  // linearly from 1 (closest) to 0 (band edge): the contact point moves continuously
  // when two pairs swap places.
  const Real best = std::sqrt(best2);
  const Real band = Real(kTieBand) * Real(cr.contact_distance), inv_band = Real(1) / band;
  const Real reach2 = (best + band) * (best + band);
  Real wsum = 0;
  bool first = true;
  for (int k = 0; k < nc; ++k) {
    const Cand& q = cand[k];
    if (q.dist2 == best2 && first) {
      g.sw = sws[q.iw], g.sf = sfs[q.jf], g.a = q.a, g.b = q.b;
      first = false;
    }
    if (q.dist2 >= reach2) continue;
    const Real wq = Real(1) - (std::sqrt(q.dist2) - best) * inv_band;
    if (wq <= Real(0)) continue;
    wsum += wq;
    g.d += wq * q.d;
    const int iw = sws[q.iw] - (kw - 1), jf = sfs[q.jf] - (kf - 1);
    g.ww[iw] += wq * (Real(1) - q.a);
    g.ww[iw + 1] += wq * q.a;
    g.wf[jf] += wq * (Real(1) - q.b);
    g.wf[jf + 1] += wq * q.b;
  }
  const Real inv = Real(1) / wsum;
  g.d *= inv;
  for (int k = 0; k < 3; ++k) g.ww[k] *= inv, g.wf[k] *= inv;
  g.dist = best;
  g.ok = true;
  return g;
}

// Is the contact point at an end of the yarn beyond which it has no segment, with the
// partner lying beyond that end? Then the partner has slipped off (ravelled out).
template <class Real>
RAVEL_INLINE bool YarnContact<Real>::slipped_off(int yarn, int seg, Real frac, const V3& toward_partner) const {
  const bool at_end = frac >= Real(1) - Real(1e-6) && !seg_ok(yarn, seg + 1) &&
                      !(seg + 2 == model_.yarn_size(yarn) && !(model_.yarn_end_free[yarn] & 2));
  const bool at_start =
      frac <= Real(1e-6) && !seg_ok(yarn, seg - 1) && !(seg == 0 && !(model_.yarn_end_free[yarn] & 1));
  if (!at_end && !at_start) return false;
  const V3 t = s_.x[ynode(yarn, seg + 1)] - s_.x[ynode(yarn, seg)];
  const Real L = t.norm();
  if (L <= Real(0)) return false;
  const Real along = toward_partner.dot(t) / L;
  const Real dist = toward_partner.norm();
  return at_end ? along > Real(0.5) * dist : -along > Real(0.5) * dist;
}

// Material coordinate (node index + fraction) of point p along a yarn near node k:
// projection on the chord joining k's neighbours (unit direction returned in `tangent`).
template <class Real>
inline double YarnContact<Real>::chord_coord(int yarn, int k, const V3* xs, const bool* seg, const V3& p,
                                             V3& tangent) const {
  // xs: positions of nodes k-1, k, k+1; seg: segments k-1 and k intact (a Window's).
  const int km = seg[0] ? k - 1 : k;
  const int kp = seg[1] ? k + 1 : k;
  V3 xm = xs[km - k + 1];
  int span = kp - km;
  const int ax = model_.yarn_start_mirror[yarn];
  if (k == 0 && ax >= 0 && kp == 1) {
    // Node 0 sits on a symmetry plane: its other neighbour is node 1's mirror image, and
    // contacts on the mirror side belong to the mirror crossing (offset clamped to >= 0).
    xm = xs[2];
    xm[ax] = -xm[ax];
    span = 2;
  }
  const V3 T = xs[kp - k + 1] - xm;
  const Real T2 = T.squaredNorm();
  if (span == 0 || T2 <= Real(0)) {
    tangent.setZero();
    return k;
  }
  tangent = T * (Real(1) / std::sqrt(T2));
  // Projection on the chord, mapped piecewise so that the nodes keep their own coordinates:
  // node k - 1, k, k + 1 project to k - 1, k, k + 1 whatever the chord's proportions. A
  // linear map centred on node k gave a point between nodes k and k + 1 a coordinate that
  // differed from the one the next node's chord gives it, so a contact jumped (by up to 30
  // um on yarns bent at the free edges) when its tracked node changed: a slip that no yarn
  // made, with friction against it.
  const double h = double((p - xs[1]).dot(T) / T2);
  double off = h * double(span);
  if (span == 2) {
    const double tk = double((xs[1] - xm).dot(T) / T2);  // node k's own place on the chord
    if (tk > lanes::kChordNodeMin && tk < 1 - lanes::kChordNodeMin) off = h < 0 ? h / tk : h / (1 - tk);
  }
  const double lo = (k == 0 && ax >= 0) ? 0.0 : double(km - k);
  return k + std::clamp(off, lo, double(kp - k));
}

// The two nodes and fraction of a material coordinate.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::coord_nodes(int yarn, double u, int& n0, int& n1, Real& frac) const {
  const int s = std::clamp(floor_int(u), 0, model_.yarn_size(yarn) - 2);
  frac = Real(std::clamp(u - s, 0.0, 1.0));
  n0 = ynode(yarn, s);
  n1 = ynode(yarn, s + 1);
}

// The closest points of the crossings c in [c0, c1) with on[c - c0] set, from their loaded
// windows: the lane windows together in lanes (when on and the processor has them; the
// same numbers bit for bit), the others one at a time.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::closest_batch(int c0, int c1, const bool* on, const Window* w, ContactGeom* g,
                                                   lanes::ClosestBatch& lb) const {
  int lane[kBatch];
  int nl = 0;
  for (int c = c0; c < c1; ++c) {
    const int k = c - c0;
    lane[k] = -1;
    if (!on[k]) continue;
    const Crossing& cr = model_.crossings[c];
    if constexpr (std::is_same_v<Real, double>) {
      if (lane_window(w[k])) {
        lb.xw[nl] = w[k].xw[0].data();  // V3 xw[3]: 9 consecutive doubles
        lb.xf[nl] = w[k].xf[0].data();
        lb.band[nl] = double(Real(kTieBand) * Real(cr.contact_distance));
        lb.side[nl] = cr.side;
        lane[k] = nl++;
        continue;
      }
    }
    g[k] = closest(cr, w[k]);
  }
  if (nl > 0) {
    // Unused lanes repeat lane 0 (their results are not read).
    for (int l = nl; l < lanes::kWidth; ++l)
      lb.xw[l] = lb.xw[0], lb.xf[l] = lb.xf[0], lb.band[l] = lb.band[0], lb.side[l] = lb.side[0];
    lanes::closest4(lb);
    for (int k = 0; k < c1 - c0; ++k) {
      const int l = lane[k];
      if (l < 0) continue;
      ContactGeom& q = g[k];
      q.ok = true;
      q.sw = w[k].kw - 1 + int(lb.iw[l]);
      q.sf = w[k].kf - 1 + int(lb.jf[l]);
      q.a = Real(lb.a[l]);
      q.b = Real(lb.b[l]);
      q.d = V3(Real(lb.d[0][l]), Real(lb.d[1][l]), Real(lb.d[2][l]));
      q.dist = Real(lb.dist[l]);
      for (int n = 0; n < 3; ++n) q.ww[n] = Real(lb.ww[n][l]), q.wf[n] = Real(lb.wf[n][l]);
      q.lane = l;
      q.moved = lb.moved[l] != 0;
    }
  }
}

// Each thread's share of the batches in proportion to its speed in this step (batches per
// second), moved a fifth of the way from the present split, so that one step in which the
// host took a thread's core does not swing it. The cost moves over the fabric during a run
// (the impact region is dearer early, the far field later), so no fixed split balances it.
// Measured on the default scene to 102 us at two threads, the difference of the two
// threads' batch times summed over the steps (what the earlier one waits at the barrier):
// even split 0.07-0.20 s (mean 0.14, 7 runs), this 0.03-0.10 s (mean 0.07, 4 runs) in runs
// of about 2 s; moving half-way, 0.04-0.21 s (mean 0.09, 7 runs).
template <class Real>
void YarnContact<Real>::rebalance_batches(int nb) {
  const int T = int(ctx_.batch_busy.size());
  if (nb < T) return;
  double speed_sum = 0;
  for (int k = 0; k < T; ++k) {
    const int n = ctx_.batch_bound[k + 1] - ctx_.batch_bound[k];
    if (n <= 0 || !(ctx_.batch_busy[k] > 0)) return;  // no measure: keep the split
    speed_sum += n / ctx_.batch_busy[k];
  }
  double end = 0;
  for (int k = 0; k + 1 < T; ++k) {
    const int n = ctx_.batch_bound[k + 1] - ctx_.batch_bound[k];
    const double fair = nb * (n / ctx_.batch_busy[k]) / speed_sum;
    end += n + 0.2 * (fair - n);
    // At least one batch for every thread on either side of the bound.
    ctx_.batch_bound[k + 1] = std::clamp(int(std::lround(end)), ctx_.batch_bound[k] + 1, nb - (T - 1 - k));
  }
}

template <class Real>
void YarnContact<Real>::run() {
  const int nc = int(model_.crossings.size());
  const int N = model_.contact_iterations;
  ctx_.moved.resize(nc);
  ctx_.tally.assign(std::max(1, ctx_.threads), ContactTally{});
  ctx_.node_book.assign(std::max(1, ctx_.threads), NodeBook{});
  ctx_.shifted_part.resize(std::max(1, ctx_.threads));
  for (auto& part : ctx_.shifted_part) part.clear();  // (a smaller team leaves some unused)
  ctx_.chunk_first.assign(std::max(1, ctx_.threads), 0);
  ctx_.chunk_last.assign(std::max(1, ctx_.threads), 0);
  ctx_.impulses.resize(nc);  // (each crossing's fn_step, ft, event and comp_u are cleared by its first pass)
  const int T = std::max(1, ctx_.threads), nb = (nc + kBatch - 1) / kBatch;
  if (int(ctx_.batch_bound.size()) != T + 1 || ctx_.batch_bound.back() != nb) {
    ctx_.batch_bound.resize(T + 1);
    for (int k = 0; k <= T; ++k) ctx_.batch_bound[k] = int(long(nb) * k / T);
  }
  ctx_.batch_busy.assign(T, 0.0);
  for (int pass = 1; pass <= N; ++pass) {
    // alpha_n = 1/sqrt(N - n + 1): the last pass applies the full remainder (SPEC §4).
    const Real alpha = Real(1.0 / std::sqrt(double(N - pass + 1)));
    const bool first = pass == 1, last = pass == N;
    // Every crossing's corrections from the same state (Jacobi), then applied: each
    // thread owns a range of nodes and applies, in crossing order, the changes that
    // fall in its range: race-free, and the same sums whatever the number of threads.
    // One thread runs the same code (gathering each batch as it was done instead saved 2 %
    // of a one-thread step, not worth a second path).
    ctx_.rec_first.resize(nc);
    ctx_.rec_last.resize(nc);
#pragma omp parallel num_threads(ctx_.threads)
    {
      // Each thread takes a contiguous run of batches, split by their cost in the last step
      // (rebalance_batches): the one-crossing code for held nodes, symmetry planes and yarn
      // ends makes some runs dearer. The split does not change a result.
      int t, team, b0, b1;
      my_team(t, team);
      if (team == T)
        b0 = ctx_.batch_bound[t], b1 = ctx_.batch_bound[t + 1];
      else
        my_share(nb, b0, b1, t);
      const int cb0 = std::min(nc, b0 * kBatch), cb1 = std::min(nc, b1 * kBatch);
      const double start = T > 1 ? wall_seconds() : 0;
      for (int b = b0; b < b1; ++b) {
        const int c0 = b * kBatch, c1 = std::min(nc, (b + 1) * kBatch);
        crossing_batch(c0, c1, alpha, first, last, &ctx_.impulses[c0]);
        if (team == 1) continue;  // one thread gathers every record: no node bounds needed
        for (int c = c0; c < c1; ++c) {
          // The lowest and highest node the record can touch.
          const CrossingImpulse& r = ctx_.impulses[c];
          int a = std::numeric_limits<int>::max(), z = -1;
          auto take = [&](const int* nodes, int count) {
            for (int k = 0; k < count; ++k)
              if (nodes[k] >= 0) a = std::min(a, nodes[k]), z = std::max(z, nodes[k]);
          };
          if (r.has_n || r.has_s || r.has_c) take(r.node, 6);
          if (r.has_f) take(r.fnode, 4);
          ctx_.rec_first[c] = a;
          ctx_.rec_last[c] = z;
        }
      }
      if (T > 1 && team == T) ctx_.batch_busy[t] += wall_seconds() - start;
      // Running maximum of the highest node and running minimum (from the end) of the
      // lowest: a node range [lo, hi) is touched only by records between the first
      // crossing whose running maximum reaches lo and the last whose running minimum is
      // below hi. With the node numbering of model.cpp that is about 1/T of them each.
      // Each thread runs them over its own crossings, then takes in the other threads'
      // ends (two serial sweeps over all crossings here took about 2 % of the main thread's
      // time in a two-thread step, the other thread waiting).
      int lo, hi, c_first = 0, c_end = nc;
      my_share(model_.node_count, lo, hi, t);
      if (team > 1) {
        int* rl = ctx_.rec_last.data();
        int* rf = ctx_.rec_first.data();
        for (int c = cb0 + 1; c < cb1; ++c) rl[c] = std::max(rl[c], rl[c - 1]);
        for (int c = cb1 - 2; c >= cb0; --c) rf[c] = std::min(rf[c], rf[c + 1]);
        ctx_.chunk_last[t] = cb1 > cb0 ? rl[cb1 - 1] : -1;
        ctx_.chunk_first[t] = cb1 > cb0 ? rf[cb0] : std::numeric_limits<int>::max();
#pragma omp barrier
        int before = -1, after = std::numeric_limits<int>::max();
        for (int u = 0; u < t; ++u) before = std::max(before, ctx_.chunk_last[u]);
        for (int u = t + 1; u < team; ++u) after = std::min(after, ctx_.chunk_first[u]);
        // (the running bounds are monotone, so only a leading / trailing run of them changes)
        for (int c = cb0; c < cb1 && rl[c] < before; ++c) rl[c] = before;
        for (int c = cb1 - 1; c >= cb0 && rf[c] > after; --c) rf[c] = after;
#pragma omp barrier
        c_first = int(std::lower_bound(ctx_.rec_last.begin(), ctx_.rec_last.end(), lo) - ctx_.rec_last.begin());
        c_end = int(std::lower_bound(ctx_.rec_first.begin(), ctx_.rec_first.end(), hi) - ctx_.rec_first.begin());
      }
      for (int c = c_first; c < c_end; ++c) gather(ctx_.impulses[c], lo, hi);
      if (last)
        finish_last_pass(lo, hi, ctx_.node_book[t], ctx_.shifted_part[t]);
      else
        finish_pass(lo, hi);
      if (last) {
        // Once every node has its corrections, per crossing: how far the two yarns'
        // material moved against each other this step, and the step's sums, each thread
        // over its share of the crossings (a serial loop here was 5 % of a two-thread step,
        // which the other thread spent waiting).
#pragma omp barrier
        int c_lo, c_hi;
        my_share(nc, c_lo, c_hi, t);
        for (int c = c_lo; c < c_hi; ++c) moved_since_last(c, ctx_.tally[t]);
      }
    }
  }
  if (T > 1) rebalance_batches(nb);
  // The sums of the thread shares in thread order; what broke the method's assumptions
  // booked in crossing order.
  ContactTally sum;
  for (int t = 0; t < ctx_.threads; ++t) {
    const ContactTally& p = ctx_.tally[t];
    sum.fn += p.fn, sum.comp_u += p.comp_u, sum.stick_e += p.stick_e;
    sum.sliding += p.sliding, sum.stuck += p.stuck, sum.events = sum.events || p.events;
  }
  run_.yarn_force = sum.fn;
  s_.book.compress_end = sum.comp_u;
  s_.book.stick_end = sum.stick_e;
  run_.sliding_count = sum.sliding;
  run_.stuck_count = sum.stuck;
  if (!sum.events) return;
  for (int c = 0; c < nc; ++c) {
    std::uint8_t ev = s_.cr[c].event;
    if (!ev) continue;
    const Real moved = ctx_.moved[c];
    const Crossing& cr = model_.crossings[c];
    auto note = [&](long& count, double& t, int& i, int& j) {
      if (count++ == 0) t = run_.time, i = cr.grid_i, j = cr.grid_j;
    };
    // A pair that moved more than one node while the yarns moved less than half a node
    // against each other was re-chosen by the changed shape (yarns folded, bunched or apart
    // near the projectile), not outrun: a smaller time step would not change it.
    if ((ev & ev_skip) && moved < Real(0.5) * Real(model_.elem_rest[model_.yarn_elem_offset[cr.warp_yarn]])) {
      ev &= std::uint8_t(~ev_skip);
      note(run_.diag.repaired, run_.diag.first_repair_time, run_.diag.first_repair_i, run_.diag.first_repair_j);
    }
    if (ev & ev_skip)
      note(run_.diag.skipped_nodes, run_.diag.first_skip_time, run_.diag.first_skip_i, run_.diag.first_skip_j);
    if (ev & ev_ravel)
      note(run_.diag.ravelled, run_.diag.first_ravel_time, run_.diag.first_ravel_i, run_.diag.first_ravel_j);
    if (ev & ev_lost)
      note(run_.diag.lost_segments, run_.diag.first_ravel_time, run_.diag.first_ravel_i, run_.diag.first_ravel_j);
    if (ev & ev_pass)
      note(run_.diag.passed_through, run_.diag.first_pass_time, run_.diag.first_pass_i, run_.diag.first_pass_j);
    if (ev & ev_separated) ++run_.diag.separated;
  }
}

// How far the two yarns' material moved against each other this step: the offset of last
// step's tracked node pair, then and now (the pair may have been re-chosen since), kept in
// the context for the step's event booking; the pair becomes next step's "last". An active
// crossing's material slip is bounded by it: the stick point's advance, but never faster
// than the yarns move against each other (a jump of the closest point along a kinked or
// re-paired yarn is not slip). The crossing's share of the step's sums goes to `tally`.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::moved_since_last(int c, ContactTally& tally) {
  CrossingState<Real>& x = s_.cr[c];
  const LastPair was = x.last;
  const V3 now = pair_offset(model_, s_, c, was.kw, was.kf);
  const Real moved = (now - was.offset).norm();
  // (the same pair as last step, the common case: the same offset)
  x.last = {x.kw, x.kf, x.kw == was.kw && x.kf == was.kf ? now : pair_offset(model_, s_, c, x.kw, x.kf)};
  ctx_.moved[c] = moved;
  if (x.event) tally.events = true;
  if (!x.active) return;
  x.slip = std::min(x.slip, double(moved) / double(model_.dt));
  x.heat += x.ft * x.slip * model_.dt;
  tally.fn += x.fn;
  tally.comp_u += x.comp_u;
  tally.stick_e += x.stick_e;
  if (x.fn > 0) (x.sliding ? tally.sliding : tally.stuck)++;
}

template <class Real>
RAVEL_INLINE void YarnContact<Real>::gather(const CrossingImpulse& r, int lo, int hi) {
  if (!r.any_held) {
    // The common case, no held node: every weight on a node in [lo, hi) goes to the sums.
    const unsigned span = unsigned(hi - lo);
    auto each = [lo, span](int count, const int* nodes, const Real* w, const V3 q, PassSum* __restrict sum,
                           V3 PassSum::*part) {
      for (int k = 0; k < count; ++k)
        if (unsigned(nodes[k] - lo) < span && w[k] != Real(0)) sum[nodes[k]].*part += w[k] * q;
    };
    PassSum* sum = s_.pass_sum.data();
    if (r.has_n) each(6, r.node, r.w, r.P, sum, &PassSum::n);
    if (r.has_f) each(4, r.fnode, r.fw, r.F, sum, &PassSum::f);
    if (r.has_s) each(6, r.node, r.w, r.S, sum, &PassSum::s);
    if (r.has_c) each(6, r.node, r.w, r.C, sum, &PassSum::c);
    return;
  }
  // One kind of correction: weights w on nodes, times the vector q.
  auto each = [&](int count, const int* nodes, const Real* w, const V3& q, V3 PassSum::*sum, auto&& take_held) {
    for (int k = 0; k < count; ++k) {
      const int i = nodes[k];
      if (unsigned(i - lo) >= unsigned(hi - lo) || w[k] == Real(0)) continue;  // i in [lo, hi), -1 not
      if (s_.held_flag[i])
        take_held(i, w[k] * q);
      else
        s_.pass_sum[i].*sum += w[k] * q;
    }
  };
  if (r.has_n)
    each(6, r.node, r.w, r.P, &PassSum::n,
         [&](int i, const V3& p) { apply_impulse(i, p, &Corrections::dv_contact, r.hold, nullptr); });
  if (r.has_f)
    each(4, r.fnode, r.fw, r.F, &PassSum::f,
         [&](int i, const V3& p) { apply_impulse(i, p, &Corrections::dv_friction, r.hold, &s_.held_fric); });
  if (r.has_s) each(6, r.node, r.w, r.S, &PassSum::s, [&](int i, const V3& dx) { shift_node(i, dx, r.hold); });
  if (r.has_c)
    each(6, r.node, r.w, r.C, &PassSum::c,
         [&](int i, const V3& p) { apply_impulse(i, p, &Corrections::dv_compress, r.hold, &s_.held_comp); });
}

// Node i's share of the pass: its sums times 1/m, zero on its fixed axes (dvc only with a
// compression law); the sums cleared for the next pass.
template <class Real>
RAVEL_INLINE auto YarnContact<Real>::take_share(int i) -> NodeShare {
  const Real im = Real(model_.inv_mass[i]);
  const std::uint8_t fx = model_.fixed[i];
  PassSum& sum = s_.pass_sum[i];
  NodeShare p{im * sum.n, im * sum.f, im * sum.s, V3::Zero()};
  sum.n.setZero();
  sum.f.setZero();
  sum.s.setZero();
  if (ctx_.compressible) {
    p.dvc = im * sum.c;
    sum.c.setZero();
  }
  if (fx) {
    zero_fixed(p.dvn, fx);
    zero_fixed(p.dvf, fx);
    zero_fixed(p.dx, fx);
    zero_fixed(p.dvc, fx);
  }
  return p;
}

// Apply the pass's gathered sums to the nodes in [lo, hi).
template <class Real>
RAVEL_INLINE void YarnContact<Real>::finish_pass(int lo, int hi) {
  const Real dt = Real(model_.dt);
  for (int i = lo; i < hi; ++i) {
    Corrections& corr = s_.corr[i];
    const NodeShare p = take_share(i);
    const V3 &dvn = p.dvn, &dvf = p.dvf, &dx = p.dx;
    V3 dv = dvn + dvf;
    if (ctx_.compressible) {
      dv += p.dvc;
      corr.dv_compress += p.dvc;
    }
    s_.v[i] += dv;
    corr.dv_contact += dvn;
    corr.dv_friction += dvf;
    s_.x[i] += dt * dv + dx;
    corr.dx_contact += dx;
  }
}

// finish_pass of the last pass, with the ledger's sweep over the nodes (Book::finish_step:
// after this pass nothing changes a node's velocity or corrections until the step ends).
// Each node's values and each sum's terms are those the ledger's own sweep took, in node
// order, so the ledger is the same to the bit; the step's velocity changes are cleared here.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::finish_last_pass(int lo, int hi, NodeBook& book, std::vector<int>& shifted) {
  if constexpr (std::is_same_v<Real, double>) {
    if (ctx_.simd) {
      // The same, a node's x y z in the lanes (contact_lanes.h: finish_nodes, the same bits).
      static_assert(sizeof(typename State<Real>::PassSum) == 12 * sizeof(double) &&
                        sizeof(typename State<Real>::Corrections) == 12 * sizeof(double) &&
                        sizeof(V3) == 3 * sizeof(double),
                    "finish_nodes reads the sums, corrections and vectors as packed doubles");
      lanes::NodeFinish f;
      f.pass_sum = s_.pass_sum[0].n.data();
      f.corr = s_.corr[0].dv_contact.data();
      f.v = s_.v[0].data();
      f.x = s_.x[0].data();
      f.v_prev = s_.v_prev[0].data();
      f.inv_mass = model_.inv_mass.data();
      f.mass = model_.mass.data();
      f.fixed = model_.fixed.data();
      f.dt = model_.dt;
      f.compressible = ctx_.compressible;
      f.lo = lo, f.hi = hi;
      shifted.resize(size_t(std::max(0, hi - lo)));
      f.shifted = shifted.data();
      lanes::finish_nodes(f);
      shifted.resize(size_t(f.shifted_count));
      book.ke = f.ke, book.w_contact = f.w_contact, book.w_friction = f.w_friction, book.w_compress = f.w_compress;
      return;
    }
  }
  const Real dt = Real(model_.dt);
  double ke = 0, w_contact = 0, w_friction = 0, w_compress = 0;
  shifted.clear();
  for (int i = lo; i < hi; ++i) {
    Corrections& corr = s_.corr[i];
    const NodeShare p = take_share(i);
    const V3 &dvn = p.dvn, &dvf = p.dvf, &dx = p.dx;
    V3 dv = dvn + dvf, dv_compress = V3::Zero();
    if (ctx_.compressible) {
      dv += p.dvc;
      dv_compress = corr.dv_compress + p.dvc;
    }
    const V3 v = s_.v[i] + dv;
    s_.v[i] = v;
    const V3 dv_contact = corr.dv_contact + dvn, dv_friction = corr.dv_friction + dvf;
    s_.x[i] += dt * dv + dx;
    const V3 dxc = corr.dx_contact + dx;
    corr.dx_contact = dxc;
    const double hm = 0.5 * model_.mass[i];
    ke += hm * double(v.squaredNorm());
    const V3 vsum = s_.v_prev[i] + v;
    w_contact += hm * double(dv_contact.dot(vsum));
    if (dxc.x() != Real(0) || dxc.y() != Real(0) || dxc.z() != Real(0)) shifted.push_back(i);
    corr.dv_contact.setZero();  // ready for the next step's corrections
    w_friction += hm * double(dv_friction.dot(vsum));
    corr.dv_friction.setZero();
    if (ctx_.compressible) {
      w_compress += hm * double(dv_compress.dot(vsum));
      corr.dv_compress.setZero();
    }
  }
  book.ke = ke, book.w_contact = w_contact, book.w_friction = w_friction, book.w_compress = w_compress;
}

// `acc`: where the node's velocity change is summed for the ledger's work of this kind of
// correction; `part`: per node, where the share passed to the projectile is also summed
// (friction and compression, whose work on the projectile is their own; null: the normal
// correction's).
template <class Real>
inline void YarnContact<Real>::apply_impulse(int i, V3 P, V3 Corrections::*acc, bool hold, std::vector<V3>* part) {
  const Real im = Real(model_.inv_mass[i]);
  if (im == Real(0)) return;
  if (hold) pass_to_projectile(s_, i, P, part);  // (hold.h)
  V3 dv = im * P;
  zero_fixed(dv, model_.fixed[i]);
  s_.v[i] += dv;
  s_.corr[i].*acc += dv;
  s_.x[i] += Real(model_.dt) * dv;  // the predicted position follows the velocity change (Eq 2)
}

// Move a node by a mass-weighted shift (no velocity change); recorded for the ledger.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::shift_node(int i, const V3& S, bool hold) {
  const Real im = Real(model_.inv_mass[i]);
  if (im == Real(0)) return;
  V3 dx = im * S;
  if (hold) keep_out(s_, i, dx);  // not into the projectile that holds it (hold.h)
  zero_fixed(dx, model_.fixed[i]);
  s_.x[i] += dx;
  s_.corr[i].dx_contact += dx;
}

// `first`: the step's first pass, which clears the crossings' per-step state.
template <class Real>
inline void YarnContact<Real>::crossing_batch(int c0, int c1, Real alpha, bool first, bool last, CrossingImpulse* out) {
  Window w[kBatch];
  ContactGeom g[kBatch];
  bool on[kBatch];
  bool tracked[kBatch];
  if (first) {
    for (int c = c0; c < c1; ++c) s_.cr[c].fn_step = 0, s_.cr[c].ft = 0, s_.cr[c].event = 0, s_.cr[c].comp_u = 0;
  }
  for (int c = c0; c < c1; ++c) {
    const int k = c - c0;
    CrossingImpulse& r = out[k];
    r.has_n = r.has_f = r.has_s = r.has_c = r.hold = r.any_held = false;
    on[k] = s_.cr[c].active;
    tracked[k] = false;
    if (!on[k]) continue;
    load_window(c, w[k]);
    // Windows the lanes take are searched there (and here again only if the pair moves).
    if (lane_window(w[k])) continue;
    if (track(c, w[k], true)) s_.cr[c].event |= ev_skip;
    tracked[k] = true;
  }
  lanes::ClosestBatch lb;
  closest_batch(c0, c1, on, w, g, lb);
  for (int c = c0; c < c1; ++c) {
    const int k = c - c0;
    if (!on[k] || tracked[k] || !g[k].moved) continue;
    // The nearest pair moved: the one-crossing search from here, then its closest points.
    if (track(c, w[k], true)) s_.cr[c].event |= ev_skip;
    g[k] = closest(model_.crossings[c], w[k]);
  }
  // The rest of each crossing, in three stages over the batch: each stage is a chain of
  // square roots and divisions, and four independent chains side by side keep the
  // processor busy where one crossing at a time would wait on each (same operations).
  bool go[kBatch];
  FrictionSetup fs[kBatch];
  for (int c = c0; c < c1; ++c)
    go[c - c0] = on[c - c0] && pass_normal(c, alpha, last, w[c - c0], g[c - c0], lb, out[c - c0]);
  // Friction (Eq 12-15) once per step, in the last pass, against the normal force of all the
  // step's passes: its Coulomb bound mu f_n then holds for the step. Applied in every pass
  // with the pass's fraction alpha_n, each pass bounded by the normal force so far, a
  // sliding contact took up to sum(alpha_n) mu f_n (2.8 at N = 4, 9.9 at N = 32) and a stuck
  // one a spring 2.2 times stiffer at N = 4, so the results moved with N without converging
  // (docs/MODEL.md §4). With one pass, as before.
  if (!last) return;
  for (int c = c0; c < c1; ++c)
    if (go[c - c0]) friction_setup(c, w[c - c0], g[c - c0], lb, out[c - c0], fs[c - c0]);
  for (int c = c0; c < c1; ++c)
    if (go[c - c0]) pass_friction(c, fs[c - c0], out[c - c0]);
}

// Normal correction of one tracked crossing in one pass, given its window and closest
// points. Returns whether the crossing goes on to friction (not released, not clamped).
template <class Real>
RAVEL_INLINE bool YarnContact<Real>::pass_normal(int c, Real alpha, bool last, const Window& w, const ContactGeom& g,
                                                 const lanes::ClosestBatch& lb, CrossingImpulse& r) {
  const Crossing& cr = model_.crossings[c];
  const Real dt = Real(model_.dt);
  if (!g.ok) {
    release(c, ev_lost);  // both adjoining segments of a yarn are broken
    return false;
  }
  // Ravelled out: the partner has slipped off a free (or broken) end.
  if (slipped_off(cr.warp_yarn, g.sw, g.a, g.d) || slipped_off(cr.weft_yarn, g.sf, g.b, V3(-g.d))) {
    release(c, ev_ravel);
    return false;
  }
  for (int k = 0; k < 3; ++k) {
    r.node[k] = w.wnode[k];
    r.node[3 + k] = w.fnode[k];
    r.w[k] = -g.ww[k];
    r.w[3 + k] = g.wf[k];
  }
  // Side test: n from the weave's fixed sign and the current segment directions (from the
  // lanes when they did this crossing: the same numbers).
  const int l = g.lane;
  V3 n;
  Real dlen;
  if (l >= 0) {
    n = V3(Real(lb.n[0][l]), Real(lb.n[1][l]), Real(lb.n[2][l]));
    dlen = Real(lb.dlen[l]);
  } else {
    n = pair_cross(w, g);
    const Real nn = n.norm();
    if (nn > Real(1e-20))
      n *= Real(cr.side) / nn;
    else
      n = V3(0, 0, Real(cr.side > 0 ? -1 : 1));
    dlen = g.d.norm();
  }
  // d / |d| ((-d) / |d| is its negative exactly).
  auto unit_d = [&] {
    return l >= 0 ? V3(Real(lb.ud[0][l]), Real(lb.ud[1][l]), Real(lb.ud[2][l])) : V3(g.d * (Real(1) / dlen));
  };
  const Real D = Real(cr.contact_distance);
  Real delta;
  V3 u;
  if (g.d.dot(n) >= Real(0)) {
    delta = D - g.dist;
    u = dlen > Real(1e-12) * D ? unit_d() : n;
  } else {
    if (g.dist > D && s_.cr[c].gap > 0) {
      // On the "wrong" side by more than D, but apart (|d| > D) at the end of the last
      // step too: the yarns never came within D of each other, so they did not pass
      // through each other (that takes far less than D of relative motion per step); the
      // side test flipped because a tracked segment turned over (flung ends after
      // perforation). There is no contact to keep: released quietly.
      release(c, ev_separated);
      return false;
    }
    if (g.dist > D) {
      // Passed through by more than a yarn diameter: a correction of more than 2D in one
      // step; the nearest-pair assumption is broken here.
      release(c, ev_pass);
      return false;
    }
    delta = D + g.dist;
    u = dlen > Real(1e-12) * D ? V3(-unit_d()) : n;
  }
  // A crossing on a symmetry plane is its own mirror image: its mirror contact pair ties
  // with this one, and the pair's mean direction has no component across the plane.
  if ((model_.mirror_x && cr.grid_i == 0) || (model_.mirror_y && cr.grid_j == 0)) {
    if (model_.mirror_x && cr.grid_i == 0) u.x() = 0;
    if (model_.mirror_y && cr.grid_j == 0) u.y() = 0;
    const Real un = u.norm();
    u = un > Real(0) ? V3(u / un) : n;
  }
  // Effective inverse mass of the relative motion of the two contact points.
  // A node the projectile holds does not yield into it (see release_held).
  // Where the projectile holds both yarns so that they could only separate into it, the
  // rigid body cannot resolve the contact: the yarn contact then moves them as before.
  Real winv = 0, winv_free = 0;
  for (int k = 0; k < 6; ++k) {
    const int i = r.node[k];
    if (i < 0) continue;
    const Real wi = r.w[k] * r.w[k] * Real(model_.inv_mass[i]);
    winv_free += wi;
    if (!s_.held_flag[i]) {
      winv += wi;  // free = 1 exactly
      continue;
    }
    r.any_held = true;
    winv += wi * held_mobility(s_, i, r.w[k], u);  // (hold.h)
  }
  r.hold = crossing_keeps_hold(winv, winv_free);  // (hold.h)
  if (!r.hold) winv = winv_free;
  if (winv <= Real(0)) return false;  // every node clamped
  // Transverse compression (docs/MODEL.md §4): between the rest distance D and the
  // flattened distance c_min the crossing is a compliant contact; below c_min it is the
  // paper's rigid one. Rigid crossings have c_min = D, and everything below is as before.
  const Real span = ctx_.compressible ? D - Real(cr.flattened_distance) : Real(0);  // compressible distance D - c_min
  const Real floor_pen = delta - span;                                              // penetration below c_min
  const bool compliant = span > Real(0) && delta > Real(0);
  // With the split, the approach speed of the two contact points along u bounds the
  // velocity change a correction may make (see below).
  Real approach = 0;
  if (model_.split_penetration && (floor_pen > Real(0) || compliant)) {
    Real vrel = 0;
    for (int k = 0; k < 6; ++k)
      if (r.node[k] >= 0) vrel += r.w[k] * s_.v[r.node[k]].dot(u);
    approach = std::max(Real(0), -vrel);
  }
  Real P = 0;
  if (floor_pen > Real(0)) {
    // Eq 9-10 with node masses: a relative displacement alpha * floor_pen within the step.
    Real dv = floor_pen / dt;
    if (model_.split_penetration) {
      // Only the part of the penetration this step's approach made is removed by a velocity
      // change (which then leaves the contact at rest: inelastic, as in the paper);
      // penetration already there before the step is removed by moving the nodes, so no
      // separating velocity (energy) is injected. See docs/MODEL.md.
      dv = std::min(dv, approach);
      approach -= dv;
      const Real shift = floor_pen - dv * dt;
      if (shift > Real(0)) {
        // A compressible crossing's shift is paced (compressed_shift), below its floor too.
        r.S = (alpha * (span > Real(0) ? compressed_shift(shift, D) : shift) / winv) * u;
        r.has_s = true;
      }
    }
    P = alpha * dv / winv;
    r.P = P * u;
    r.has_n = P > Real(0);
  }
  if (compliant) compress(c, alpha, last, std::min(span, span - delta), span, winv, P, approach, u, r);
  s_.cr[c].fn_step += double(P / dt);  // Eq 11
  if (last) s_.cr[c].gap = double(g.dist - D);
  return true;
}

// The compliant part of a crossing's normal contact, taken implicitly at the end of the
// correction. The law (docs/MODEL.md §4) has two stages: with s the distance above c_min,
//   s(f) = B / (1 + f / F_flat) + A / (1 + f / F_half),   A = c0 - c_pack, B = c_pack - c_min,
// the fibres packing (A, at the force scale F_half) and then flattening (B, at F_flat). With q
// the relative displacement the impulse makes (q = kap (f - f_acc), kap = dt^2 winv) and f_acc
// the normal force the crossing has already had this step, the step ends where
//   s_p + kap (f - f_acc) = s(f).
// One stage (B = 0) is the quadratic
//   s^2 + (kap (f_acc + F_half) - s_p) s - kap F_half span = 0,
// whose positive root is taken; two stages are solved for f by Newton's method from f_acc (the
// left side minus s(f) is increasing and concave in f, so the iterates rise monotonically to
// the root). An implicit update is stable at any stiffness: as f grows the law stiffens without
// bound (c -> c_min), and the explicit force of a prototype chattered there. It dissipates (like
// the rigid correction it becomes at high force): the work the impulse takes beyond the law's
// stored energy is booked as compression_loss.
// s_p: distance above c_min after the rigid part (>= 0); P: the rigid part's impulse.
namespace {
struct CompressionLaw {
  double A, Fh, B, Ff;  // packing stage (span, force), flattening stage (span, force)
  double s_of(double f) const { return A / (1 + f / Fh) + (B > 0 ? B / (1 + f / Ff) : 0.0); }
  double ds_df(double f) const {
    const double a = 1 + f / Fh, b = 1 + f / Ff;
    return -A / (Fh * a * a) - (B > 0 ? B / (Ff * b * b) : 0.0);
  }
  // The force at which the law's distance is s (0 < s <= A + B), by Newton's method from f0
  // (s_of is convex and decreasing, so iterates from the left of the root rise monotonically).
  double f_of(double s, double f0) const {
    double f = std::max(0.0, f0);
    if (s_of(f) < s) f = 0;  // start left of the root
    for (int it = 0; it < 60; ++it) {
      const double df = (s_of(f) - s) / -ds_df(f);
      f += df;
      if (std::abs(df) <= 1e-13 * (1 + f)) break;
    }
    return f;
  }
  // Stored energy at force f: the integral of f dc from c(f) to c0, sum over the stages of
  // span F (ln(1 + f / F) - (f / F) / (1 + f / F)).
  double energy(double f) const {
    auto stage = [f](double span, double F) {
      if (span <= 0) return 0.0;
      const double x = f / F;
      return span * F * (std::log1p(x) - x / (1 + x));
    };
    return stage(A, Fh) + stage(B, Ff);
  }
};
}  // namespace

template <class Real>
RAVEL_INLINE void YarnContact<Real>::compress(int c, Real alpha, bool last, Real s_p, Real span, Real winv, Real P,
                                              Real approach, const V3& u, CrossingImpulse& r) {
  const Crossing& cr = model_.crossings[c];
  const double dt = model_.dt;
  const double kap = dt * dt * double(winv), Fh = cr.compression_force;
  const double f_acc = s_.cr[c].fn_step + double(P) / dt, sp = std::max(0.0, double(s_p)), sz = double(span);
  const double B = std::max(0.0, cr.packed_distance - cr.flattened_distance);
  const CompressionLaw law{sz - B, Fh, B, cr.flattening_force};
  double s;
  if (B <= 0) {
    const double b = kap * (f_acc + Fh) - sp, k4 = 4 * kap * Fh * sz;
    const double root = std::sqrt(b * b + k4);
    s = b > 0 ? 0.5 * k4 / (b + root) : 0.5 * (root - b);  // the positive root, without cancellation
  } else if (sp >= law.s_of(f_acc)) {
    s = sp;  // already as far apart as the law asks at the force so far: no impulse
  } else {
    double f = f_acc;
    for (int it = 0; it < 60; ++it) {
      const double g = sp + kap * (f - f_acc) - law.s_of(f);
      const double df = -g / (kap - law.ds_df(f));
      f += df;
      if (std::abs(df) <= 1e-13 * (1 + f)) break;
    }
    s = sp + kap * (f - f_acc);
  }
  double q = s - sp, qv = q;
  // The force may exceed last step's only by what stops this step's approach (the rigid
  // contact's force): a crossing loads at the pace its yarns press, and unloads elastically.
  // A closure beyond that was there before the step (a yarn end snapping in, a tracking
  // move, a neighbour's shift): as with rigid contact, it is removed by moving the nodes,
  // with the force capped and the distance the law's at that force.
  const double qv_max = kap * (s_.cr[c].fn + double(approach) / (dt * double(winv)) - f_acc);
  if (model_.split_penetration && q > std::max(0.0, qv_max)) {
    qv = std::max(0.0, qv_max);
    s = B <= 0 ? Fh * sz / (f_acc + qv / kap + Fh) : law.s_of(f_acc + qv / kap);
    q = s - sp;
    const V3 S = (alpha * Real(compressed_shift(Real(q - qv), Real(cr.contact_distance))) / Real(winv)) * u;
    r.S = r.has_s ? V3(r.S + S) : S;
    r.has_s = true;
  }
  if (q > 0) {
    q *= double(alpha);
    const Real Pc = Real(double(alpha) * qv / (dt * double(winv)));
    r.C = Pc * u;
    r.has_c = Pc > Real(0);
    s_.cr[c].fn_step += double(Pc) / dt;
  } else {
    q = 0;
  }
  if (last) {
    // The law's stored energy at the distance this crossing now enforces: the integral of the
    // law's force from that distance to c0.
    const double se = std::min(sz, sp + q);
    if (B <= 0)
      s_.cr[c].comp_u = se > 0 ? Fh * (sz * std::log(sz / se) - (sz - se)) : 0.0;
    else
      s_.cr[c].comp_u = se > 0 && se < sz ? law.energy(law.f_of(se, f_acc + qv / kap)) : 0.0;
  }
}

template <class Real>
RAVEL_INLINE void YarnContact<Real>::friction_setup(int c, const Window& w, const ContactGeom& g,
                                                    const lanes::ClosestBatch& lb, CrossingImpulse& r,
                                                    FrictionSetup& s) {
  const Crossing& cr = model_.crossings[c];
  const int kw = w.kw, kf = w.kf;
  if (const int l = g.lane; l >= 0) {
    // The lanes did chord_coord for this crossing (all four window segments intact).
    s.cw = kw + double(lb.offw[l]);
    s.cf = kf + double(lb.offf[l]);
    s.Tw = V3(Real(lb.tw[0][l]), Real(lb.tw[1][l]), Real(lb.tw[2][l]));
    s.Tf = V3(Real(lb.tf[0][l]), Real(lb.tf[1][l]), Real(lb.tf[2][l]));
    s.lw.first = kw - 1;
    s.lf.first = kf - 1;
    for (int k = 0; k < 2; ++k) s.lw.len[k] = Real(lb.lw[k][l]), s.lf.len[k] = Real(lb.lf[k][l]);
  } else {
    V3 pa = V3::Zero(), pb = V3::Zero();
    for (int k = 0; k < 3; ++k) {
      if (r.node[k] >= 0) pa -= r.w[k] * w.xw[k];
      if (r.node[3 + k] >= 0) pb += r.w[3 + k] * w.xf[k];
    }
    s.cw = chord_coord(cr.warp_yarn, kw, w.xw, w.wseg, pb, s.Tw);
    s.cf = chord_coord(cr.weft_yarn, kf, w.xf, w.fseg, pa, s.Tf);
    s.lw = s.lf = KnownLengths{};
  }
  if (s_.cr[c].stick_w < 0) s_.cr[c].stick_w = s.cw, s_.cr[c].stick_f = s.cf;
  Real fa, fb;
  coord_nodes(cr.warp_yarn, s.cw, r.fnode[0], r.fnode[1], fa);
  coord_nodes(cr.weft_yarn, s.cf, r.fnode[2], r.fnode[3], fb);
  r.fw[0] = -(Real(1) - fa);
  r.fw[1] = -fa;
  r.fw[2] = Real(1) - fb;
  r.fw[3] = fb;
  s.fwinv = 0;
  for (int k = 0; k < 4; ++k) s.fwinv += double(r.fw[k] * r.fw[k]) * model_.inv_mass[r.fnode[k]];
}

// Stick or slip on each yarn, and the friction impulse of the step (Eq 12-15; called in the
// last pass, which applies its corrections in full), with the step's friction state.
template <class Real>
RAVEL_INLINE void YarnContact<Real>::pass_friction(int c, const FrictionSetup& s, CrossingImpulse& r) {
  const Crossing& cr = model_.crossings[c];
  const Real dt = Real(model_.dt);
  const double fwinv = s.fwinv;
  const double fn = s_.cr[c].fn_step;
  const double limit = model_.friction * fn;
  double ft_w = 0, ft_f = 0, moved = 0, stored = 0;
  bool slid = false;
  if (fwinv > 0) {
    // K = alpha_f m / dt^2, m the effective mass of the relative motion: alpha_f = 1
    // returns the contact to its stuck point in exactly one step.
    const double K = model_.friction_penalty / (fwinv * double(dt) * double(dt));
    auto one_yarn = [&](int yarn, double cur, double& stick, double& force, const KnownLengths& known) {
      const double slip = double(arc_between(yarn, stick, cur, known));  // Delta s of Eq 12
      const double trial = K * slip;
      if (std::abs(trial) <= limit) {
        force = trial;  // stick: A' stays the stuck point (Eq 13, phi <= 0)
      } else {
        force = std::copysign(limit, trial);  // slip: Eq 14 moves the stuck point
        const double new_stick = advance(yarn, cur, -force / K, known);
        moved += std::abs(double(arc_between(yarn, stick, new_stick, known)));
        stick = new_stick;
        slid = true;
      }
      stored += force * force / (2 * K);  // the penalty spring K/2 e^2 (stick_energy)
    };
    one_yarn(cr.warp_yarn, s.cw, s_.cr[c].stick_w, ft_w, s.lw);
    one_yarn(cr.weft_yarn, s.cf, s_.cr[c].stick_f, ft_f, s.lf);
  }
  if (ft_w != 0 || ft_f != 0) {
    // Force on the warp along its tangent, reaction on the weft; and vice versa (Eq 15).
    const V3 Fwarp = Real(ft_w) * s.Tw - Real(ft_f) * s.Tf;
    r.F = -dt * Fwarp;  // impulse on the weft point; the warp gets the reaction
    r.has_f = true;
    s_.cr[c].ft = double(Fwarp.norm());
  }
  s_.cr[c].sliding = slid;
  s_.cr[c].slip = moved / double(dt);
  s_.cr[c].fn = fn;
  s_.cr[c].stick_e = stored;
}

// The interpenetration left at the end of a step (after every correction), sampled every
// kPenetrationCheckEvery steps: what the contact algorithm failed to resolve.
template <class Real>
void YarnContact<Real>::residual_penetration() {
  const int nc = int(model_.crossings.size());
  const int nb = (nc + kBatch - 1) / kBatch;
  double worst = 0;
#pragma omp parallel for num_threads(ctx_.threads) schedule(static) reduction(max : worst) if (ctx_.threads > 1)
  for (int b = 0; b < nb; ++b) {
    const int c0 = b * kBatch, c1 = std::min(nc, c0 + kBatch);
    Window w[kBatch];
    ContactGeom g[kBatch];
    bool on[kBatch];
    for (int c = c0; c < c1; ++c) {
      on[c - c0] = s_.cr[c].active;
      if (on[c - c0]) load_window(c, w[c - c0]);
    }
    lanes::ClosestBatch lb;
    closest_batch(c0, c1, on, w, g, lb);
    for (int c = c0; c < c1; ++c) {
      const int k = c - c0;
      if (!on[k] || !g[k].ok) continue;
      const Crossing& cr = model_.crossings[c];
      const V3 n = Real(cr.side) * pair_cross(w[k], g[k]);
      // Below the flattened distance (D itself for rigid crossings): what the law forbids.
      const double D = cr.contact_distance, cmin = ctx_.compressible ? cr.flattened_distance : D;
      const double dist = double(g[k].dist);
      const double pen = g[k].d.dot(n) >= Real(0) ? cmin - dist : (dist > D ? 0.0 : cmin + dist);
      worst = std::max(worst, pen);
    }
  }
  run_.diag.max_penetration = std::max(run_.diag.max_penetration, worst);
  run_.diag.last_penetration = worst;
}

// The two precisions (solver.h: Precision).
template <class Real>
void yarn_contact(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx) {
  YarnContact<Real>{model, s, run, ctx}.run();
}

template <class Real>
void residual_penetration(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx) {
  YarnContact<Real>{model, s, run, ctx}.residual_penetration();
}

template void yarn_contact(const Model&, State<float>&, RunState&, Context<float>&);
template void yarn_contact(const Model&, State<double>&, RunState&, Context<double>&);
template void residual_penetration(const Model&, State<float>&, RunState&, Context<float>&);
template void residual_penetration(const Model&, State<double>&, RunState&, Context<double>&);

}  // namespace ravel::detail

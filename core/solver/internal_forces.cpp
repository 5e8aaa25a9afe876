// Stage internal_forces (Eq 3, 23-25): element strain -> stress, failure, bending, nodal forces.
#include <cstdint>
#include <cstring>

#include "solver/simd/element_lanes.h"
#include "solver/stage.h"

namespace ravel::detail {
namespace {

// The stage's inputs, bound for its helpers.
template <class Real>
struct InternalForces {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  static constexpr int kBatch = lanes::kWidth;
  // A failing element whose strain without the last step's position shifts was below this
  // share of the failure strain was broken by the shifts (broken_by_shift). The shifts' pace
  // (0.02 D per crossing and step, yarn_contact) moves a strain by at most a few tenths of a
  // per cent, so an element pushed over the threshold by it comes from above 0.9 and is not
  // counted; the artefact this catches took elements from about zero to 6-9 %.
  static constexpr double kShiftBreakShare = 0.9;
  const Model& model_;
  State<Real>& s_;
  RunState& run_;
  Context<Real>& ctx_;

  bool element_one(int e, bool zener, double E, double fail, bool breakable, double& stored, double& diss,
                   double& released, double& max_strain, double& damp);
  // The element law at rest length `rest`, the state untouched: the pull along the element
  // (N) and the energy its step would store and dissipate (J). The slipping clamp's slider.
  struct LawAt {
    double force, stored, dissipated;
  };
  LawAt law_at(int e, Real len, double rest, double rest_was, bool zener, double E) const;
  double feed_from_clamp(int e, Real len, bool zener, double E);
  void run();
  bool broken_by_shift(int e) const;
};

// Whether element e, failing now, was stretched to failure by the position shifts of the last
// step's contacts (penetration left from earlier steps, removed by moving nodes; not yet
// cleared, free_update does that): without them its strain was below kShiftBreakShare of
// the failure strain. Such a break is the contact method's, not the yarn's (the run's
// warnings report it; docs/MODEL.md §4).
template <class Real>
bool InternalForces<Real>::broken_by_shift(int e) const {
  const int a = model_.elem_a[e], b = model_.elem_b[e];
  const V3 dx0 = (s_.x[b] - s_.corr[b].dx_contact) - (s_.x[a] - s_.corr[a].dx_contact);
  Real eps = dx0.norm() / Real(elem_rest_now(model_, s_, e)) - Real(1), mat = eps, dg = Real(1);
  if (model_.crimp_strain > 0) crimp_stage(model_, eps, mat, dg);
  return double(eps) < kShiftBreakShare * model_.failure_strain;
}

template <class Real>
typename InternalForces<Real>::LawAt InternalForces<Real>::law_at(int e, Real len, double rest, double rest_was,
                                                                  bool zener, double E) const {
  Real eps = len / Real(rest) - Real(1), mat = eps, dg = Real(1);
  if (model_.crimp_strain > 0) crimp_stage(model_, eps, mat, dg);
  const double vol = model_.elem_area[e] * rest;
  // The yarn fed in comes out of the clamp unstrained: the element's internal and previous
  // strains are its old material's, spread over the longer rest length.
  const double dilute = rest_was / rest;
  if (zener) {
    const ZenerStep zs = ctx_.zener.step(double(s_.prev_strain[e]) * dilute, double(mat), double(s_.ev[e]) * dilute);
    return {zs.stress * double(dg) * model_.elem_area[e], zener_stored(ctx_.zener.c, zs.stress, zs.ev) * vol,
            zs.dissipated * vol};
  }
  const double sig = mat > 0 ? E * double(mat) : 0.0;
  return {sig * double(dg) * model_.elem_area[e], sig * sig / (2 * E) * vol, 0.0};
}

// A slipping clamp (docs/MODEL.md §7) feeds yarn into its element while the element pulls
// harder than the grip: a rigid-plastic slider in series with the element, so the rest
// length grows until the pull is the grip (bisection: the pull falls as the rest length
// grows, and is none at the element's present length). The clamp's friction is what the
// element took in this step and does not hold: the work its nodes did on it, in the
// leapfrog's measure (the mean of last step's pull and this step's, the grip, over its
// stretch), less what it now stores and dissipates. (The energy of the overstretched element
// less that of the fed one would also book the stretch past the grip the nodes never felt,
// 9 % too much on a single yarn at the default step, first order in dt.) Returns the
// element's rest length for this step.
template <class Real>
double InternalForces<Real>::feed_from_clamp(int e, Real len, bool zener, double E) {
  const int g = model_.grip_of_elem[e];
  s_.grip_heat[size_t(g)] = 0;
  // Fed out past the clamp's depth, the yarn has left the clamp: no grip holds it.
  const double fed_out = s_.grip_payout[size_t(g)], rest = elem_rest_now(model_, s_, e);
  const double grip = fed_out < model_.clamp_depth ? model_.grips[size_t(g)].force : 0.0;
  const LawAt held = law_at(e, len, rest, rest, zener, E);
  if (held.force <= grip || double(len) <= rest) return rest;
  double lo = rest, hi = double(len);
  for (int it = 0; it < 64 && hi - lo > 1e-14 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (law_at(e, len, mid, rest, zener, E).force > grip ? lo : hi) = mid;
  }
  const LawAt fed = law_at(e, len, hi, rest, zener, E);
  const double len_was = rest * (1 + double(s_.strain[e])) * (1 + model_.crimp_strain);
  const double pull_was = double(s_.elem_force[e].norm());
  s_.grip_heat[size_t(g)] =
      0.5 * (pull_was + fed.force) * (double(len) - len_was) - (fed.stored + fed.dissipated - s_.elem_energy[e]);
  s_.grip_payout[size_t(g)] = hi - model_.elem_rest[e];
  const Real dilute = Real(rest / hi);
  s_.ev[e] *= dilute;
  s_.prev_strain[e] *= dilute;
  return hi;
}

// One element's strain, stress update, failure and force (the one-element code the lanes mirror).
// Returns whether the element failed in this step.
template <class Real>
inline bool InternalForces<Real>::element_one(int e, bool zener, double E, double fail, bool breakable, double& stored,
                                              double& diss, double& released, double& max_strain, double& damp) {
  if (s_.broken_flag[e]) {
    s_.elem_force[e].setZero();
    return false;
  }
  const V3 dx = s_.x[model_.elem_b[e]] - s_.x[model_.elem_a[e]];
  if (!ctx_.elem_mid.empty()) {  // the midpoint for the bending lanes (bend4's operations)
    const V3 mid = Real(0.5) * (s_.x[model_.elem_a[e]] + s_.x[model_.elem_b[e]]);
    for (int m = 0; m < 3; ++m) ctx_.elem_mid[size_t(m) * size_t(model_.element_count) + size_t(e)] = double(mid[m]);
  }
  const Real len = dx.norm();
  const double rest = model_.grip_of_elem.empty() || model_.grip_of_elem[e] < 0 ? model_.elem_rest[e]
                                                                                : feed_from_clamp(e, len, zener, E);
  Real eps = len / Real(rest) - Real(1);
  const double vol = model_.elem_area[e] * rest;
  // The yarn law's strain (the crimp stage's material strain for the pin-jointed model),
  // and the force factor d(material strain)/d(strain): a crimped element's force is
  // sigma A g'(e), the derivative of its stored energy.
  Real mat = eps, dg = Real(1);
  const double apparent = double(eps);  // against L0 (crimp_stage turns eps into the yarn's own strain)
  if (model_.crimp_strain > 0) crimp_stage(model_, eps, mat, dg);
  const double mat_prev = double(s_.prev_strain[e]);
  double sig, u, dd = 0;
  if (zener) {
    const ZenerStep zs = ctx_.zener.step(double(s_.prev_strain[e]), double(mat), double(s_.ev[e]));
    s_.ev[e] = Real(zs.ev);
    sig = zs.stress;
    u = zener_stored(ctx_.zener.c, sig, zs.ev) * vol;
    dd = zs.dissipated * vol;
  } else {
    sig = mat > 0 ? E * double(mat) : 0.0;
    u = sig * sig / (2 * E) * vol;
  }
  // Snap damping (solver.snap_damping, docs/MODEL.md §3): in the step a slack element turns
  // taut its stress gains beta E_inst times its strain rate, never below zero; the work is
  // booked as damping_J. Elements that stay taut (the waves) are not damped.
  double sig_total = sig;
  if (sig > 0 && ctx_.damping_k > 0 && s_.stress[e] == Real(0)) {
    const double de = double(mat) - mat_prev;
    sig_total = std::max(0.0, sig + ctx_.damping_k * de * ctx_.zener.inv_dt);
    damp += (sig_total - sig) * de * vol;
  }
  // Crimp damping (yarn.crimp_damping, pin-jointed only, docs/MODEL.md §1): a taut element's
  // force gains beta E A times its apparent strain rate, never below zero. It damps the
  // lattice ringing a soft-then-stiff crimp stage radiates behind a steep front; slower waves
  // are damped in proportion to their frequency. Its work is booked as damping_J, over each
  // step's stretch at the mean of the damping stress at its two ends (the trapezoid; booking
  // the end-of-step stress alone made the ledger error first order in dt).
  double sig_force = sig_total * double(dg);
  if (ctx_.crimp_damping_k > 0) {
    // s_.strain[e] still holds last step's own strain: its apparent strain a step ago.
    const double de = apparent - ((1 + double(s_.strain[e])) * (1 + model_.crimp_strain) - 1);
    double extra = 0;
    if (sig > 0) {
      const double f = std::max(0.0, sig_force + ctx_.crimp_damping_k * de * ctx_.zener.inv_dt);
      extra = f - sig_force;
      sig_force = f;
    }
    damp += 0.5 * (double(s_.crimp_damp_stress[e]) + extra) * de * vol;
    s_.crimp_damp_stress[e] = Real(extra);
  }
  s_.prev_strain[e] = mat;
  s_.strain[e] = eps;
  diss += dd;
  if (breakable && double(eps) >= fail) {
    // Failure: the element is removed for good, its energy is released (SPEC §1). It
    // last pushed on its nodes at t - dt, over the half steps around t - dt: the energy
    // it took from them is its energy at mid-step, its energy at t - dt plus half the work
    // its stress then did over the step's change of strain. Booking the energy at t instead
    // created f v dt / 2 per break (2 % of the impact energy in a near-limit run with 240
    // breaks); the mean of t - dt and t is the same to second order but books, for an
    // element stretched past failure within one step, the quadratic energy of a stretch it
    // never resisted (20 % of the impact energy created over 4 ms of a slowly caught
    // projectile at 73 m/s).
    s_.broken_flag[e] = 1;
    released += s_.elem_energy[e] + 0.5 * double(s_.stress[e]) * vol * (double(mat) - mat_prev);
    s_.stress[e] = 0;
    if (ctx_.crimp_damping_k > 0) s_.crimp_damp_stress[e] = 0;
    s_.elem_force[e].setZero();
    return true;
  }
  s_.elem_energy[e] = u;
  stored += u;
  s_.stress[e] = Real(sig_total);
  max_strain = std::max(max_strain, double(eps));
  // Force on node b: -sigma A along the element (pulls b towards a).
  s_.elem_force[e] = len > Real(0) ? V3(dx * Real(-sig_force * model_.elem_area[e] / double(len))) : V3::Zero();
  return false;
}

// ---------------------------------------------------------------- stages
// Element strain from positions, constitutive update, failure, element force vectors,
// bending springs, then gather into nodal forces.
template <class Real>
void InternalForces<Real>::run() {
  const int ne = model_.element_count;
  const bool zener = model_.material == Material::zener;
  const double E = model_.modulus_inst;
  const double fail = model_.failure_strain;
  const bool breakable = model_.breakable;
  double stored = 0, diss = 0, released = 0, max_strain = 0, damp = 0;
  int newly_broken[2] = {0, 0}, nbroke = 0;
  const bool gripped = !model_.grip_of_elem.empty();
  // Elements in groups of four: intact groups of a Zener yarn in which nothing fails go
  // through the lanes (the same numbers; element_lanes.h), the rest one at a time. Sums are
  // taken in element order either way.
  const bool use_lanes = zener && ctx_.simd;
  const int ng = (ne + kBatch - 1) / kBatch;
  // (One parallel region with the batch's constants set once per thread, then the groups:
  // the same static split and sums as a parallel loop; setting the whole batch per group
  // was a fifth of the pin-jointed model's step in instructions.)
#pragma omp parallel num_threads(ctx_.threads) reduction(+ : stored, diss, released, nbroke, damp) \
  reduction(max : max_strain) if (ctx_.threads > 1)
  {
    [[maybe_unused]] lanes::ElementBatch b;
    if constexpr (std::is_same_v<Real, double>) {
      if (use_lanes) {
        b.x = s_.x[0].data();
        b.k1 = ctx_.zener.c.k1, b.k2 = ctx_.zener.c.k2, b.mu = ctx_.zener.c.mu;
        b.dt = ctx_.zener.dt, b.inv_dt = ctx_.zener.inv_dt, b.lam = ctx_.zener.lam, b.g = ctx_.zener.g;
        b.decay = ctx_.zener.decay, b.slack_decay = ctx_.zener.slack_decay;
        b.fail = fail;
        b.breakable = breakable;
        b.damping_k = ctx_.damping_k;
        b.crimp_strain = model_.crimp_strain;
        b.crimp_fraction = model_.crimp_fraction;
        b.crimp_width = model_.crimp_width;
        b.crimp_damping_k = ctx_.crimp_damping_k;
        b.mid_stride = ne;
      }
    }
#pragma omp for schedule(static)
    for (int grp = 0; grp < ng; ++grp) {
      const int e0 = grp * kBatch, e1 = std::min(ne, e0 + kBatch);
      if constexpr (std::is_same_v<Real, double>) {
        // A whole group, none of it broken (four flag bytes at once) or fed from a clamp.
        bool intact = use_lanes && e1 - e0 == kBatch;
        if (intact) {
          std::uint32_t flags;
          std::memcpy(&flags, &s_.broken_flag[e0], sizeof flags);
          intact = flags == 0;
          for (int e = e0; e < e1 && intact && gripped; ++e) intact = model_.grip_of_elem[e] < 0;
        }
        if (intact) {
          b.a = &model_.elem_a[e0];
          b.b = &model_.elem_b[e0];
          b.rest = &model_.elem_rest[e0];
          b.area = &model_.elem_area[e0];
          b.crimp_damp_stress = ctx_.crimp_damping_k > 0 ? &s_.crimp_damp_stress[e0] : nullptr;
          b.prev_strain = &s_.prev_strain[e0];
          b.ev = &s_.ev[e0];
          b.strain = &s_.strain[e0];
          b.stress = &s_.stress[e0];
          b.energy = &s_.elem_energy[e0];
          b.force = s_.elem_force[e0].data();
          b.mid = ctx_.elem_mid.empty() ? nullptr : &ctx_.elem_mid[size_t(e0)];
          if (lanes::zener4(b)) {
            for (int l = 0; l < kBatch; ++l) {
              diss += b.dd[l];
              damp += b.dw[l];
              if (ctx_.crimp_damping_k > 0) damp += b.cw[l];  // (element_one adds it after the snap damping's)
              stored += b.u[l];
              max_strain = std::max(max_strain, b.eps[l]);
            }
            continue;
          }
        }
      }
      for (int e = e0; e < e1; ++e)
        nbroke += element_one(e, zener, E, fail, breakable, stored, diss, released, max_strain, damp);
    }
  }
  // Count failures serially to keep the count per family (only in a step with one).
  for (int e = 0; e < ne && nbroke > 0; ++e) {
    if (s_.broken_flag[e] == 1) {
      s_.broken_flag[e] = 2;
      newly_broken[model_.yarn_family[model_.elem_yarn[e]]]++;
      if (broken_by_shift(e)) {
        if (run_.diag.shift_broken++ == 0) run_.diag.first_shift_break_time = run_.time;
      }
    }
  }
  run_.broken[0] += newly_broken[0];
  run_.broken[1] += newly_broken[1];
  // Bending: compression-only springs between midpoints of adjoining elements.
  // A spring goes with either of its elements; the energy it held then is released with them
  // (booked at the last step it acted: unbooked, a folded yarn's spring took its energy out of
  // the ledger at every break, 0.003 J a break on the 20 mm test patch, 4 % of its impact).
  const int nbend = int(model_.bend_k.size());
  double bend_stored = 0, bend_released = 0;
  auto bend_one = [&](int s, double& stored_sum, double& released_sum) {
    const int e1 = model_.bend_e1[s], e2 = model_.bend_e2[s];
    double& held = s_.bend_energy[s];
    if (s_.broken_flag[e1] || s_.broken_flag[e2]) {
      s_.bend_force[s].setZero();
      released_sum += held;
      held = 0;
      return;
    }
    const int ax = model_.bend_mirror[s];
    if (ax >= 0) {
      // Against the mirror image: midpoint distance 2 |M_ax|; pushes M away from the
      // plane. Half of the spring's energy belongs to this side of the plane.
      const Real mc = Real(0.5) * (s_.x[model_.elem_a[e1]][ax] + s_.x[model_.elem_b[e1]][ax]);
      const double comp = model_.bend_rest[s] - 2 * std::abs(double(mc));
      s_.bend_force[s].setZero();
      held = comp > 0 ? 0.25 * model_.bend_k[s] * comp * comp : 0.0;
      stored_sum += held;
      if (comp > 0) {
        s_.bend_force[s][ax] = Real(mc >= Real(0) ? 1 : -1) * Real(model_.bend_k[s] * comp);
      }
      return;
    }
    const V3 m1 = Real(0.5) * (s_.x[model_.elem_a[e1]] + s_.x[model_.elem_b[e1]]);
    const V3 m2 = Real(0.5) * (s_.x[model_.elem_a[e2]] + s_.x[model_.elem_b[e2]]);
    const V3 d = m2 - m1;
    const Real len = d.norm();
    const double r = model_.bend_rest[s], k = model_.bend_k[s], sl = double(len);
    if (sl >= r) {
      s_.bend_force[s].setZero();
      held = 0;
      return;
    }
    // Compression-only spring 1/2 k (r - s)^2, pushing midpoint 2 away from 1. Below
    // s = r/2 (a yarn folded back on itself, e.g. a broken end whipping) the potential
    // continues as k r^2/4 - k s^2/2, whose force k d stays smooth through s = 0, where
    // the cone of 1/2 k (r - s)^2 would flip direction from one step to the next.
    if (sl >= 0.5 * r) {
      held = 0.5 * k * (r - sl) * (r - sl);
      s_.bend_force[s] = d * Real(k * (r - sl) / sl);
    } else {
      held = 0.25 * k * r * r - 0.5 * k * sl * sl;
      s_.bend_force[s] = d * Real(k);
    }
    stored_sum += held;
  };
  // In groups of four: groups of intact springs off the symmetry planes go through the lanes
  // (element_lanes.h: bend4, the same numbers), the rest one at a time; the sums in spring
  // order either way (a spring apart adds nothing: its energy is +0).
  const int nbg = (nbend + kBatch - 1) / kBatch;
  const bool bend_lanes = std::is_same_v<Real, double> && ctx_.simd;
#pragma omp parallel num_threads(ctx_.threads) reduction(+ : bend_stored, bend_released) if (ctx_.threads > 1)
  {
    [[maybe_unused]] lanes::BendBatch b;
    if constexpr (std::is_same_v<Real, double>) {
      b.x = s_.x[0].data();
      b.mid_stride = ne;
    }
#pragma omp for schedule(static)
    for (int grp = 0; grp < nbg; ++grp) {
      const int s0 = grp * kBatch, s1 = std::min(nbend, s0 + kBatch);
      if constexpr (std::is_same_v<Real, double>) {
        if (bend_lanes && s1 - s0 == kBatch) {
          // Four springs between consecutive elements of one yarn (Context::bend_along, the
          // common case): intact when those five elements are (their flag bytes at once); they
          // read the element stage's midpoints. Other groups: spring by spring.
          const int first = model_.bend_e1[s0];
          bool regular;
          const bool along = ctx_.bend_along[size_t(grp)];
          if (along) {
            std::uint32_t flags;
            std::memcpy(&flags, &s_.broken_flag[first], sizeof flags);
            regular = flags == 0 && !s_.broken_flag[first + kBatch];
          } else {
            regular = true;
            for (int sp = s0; sp < s1 && regular; ++sp) {
              const int e1 = model_.bend_e1[sp], e2 = model_.bend_e2[sp];
              regular = !s_.broken_flag[e1] && !s_.broken_flag[e2] && model_.bend_mirror[sp] < 0;
            }
          }
          if (regular) {
            b.mid = along ? ctx_.elem_mid.data() : nullptr;
            b.e1 = first;
            if (!along)
              for (int l = 0; l < kBatch; ++l) {
                const int e1 = model_.bend_e1[s0 + l], e2 = model_.bend_e2[s0 + l];
                b.a1[l] = model_.elem_a[e1], b.b1[l] = model_.elem_b[e1];
                b.a2[l] = model_.elem_a[e2], b.b2[l] = model_.elem_b[e2];
              }
            b.rest = &model_.bend_rest[s0];
            b.k = &model_.bend_k[s0];
            b.force = s_.bend_force[s0].data();
            b.energy = &s_.bend_energy[s0];
            lanes::bend4(b);
            for (int l = 0; l < kBatch; ++l) bend_stored += b.held[l];
            continue;
          }
        }
      }
      for (int sp = s0; sp < s1; ++sp) bend_one(sp, bend_stored, bend_released);
    }
  }
  // Gather, and with each node's force the free update of Eq 1-2 (stage.h: free_update).
  const int n = model_.node_count;
  double max_r2 = 0;
  bool gathered = false;
  if constexpr (std::is_same_v<Real, double>) {
    if (ctx_.simd) {
      // The same, a node's x y z in the lanes (element_lanes.h: gather_forces, the same bits).
      static_assert(sizeof(V3) == 3 * sizeof(double) && sizeof(std::pair<int, Real>) == 16 &&
                        sizeof(typename State<Real>::Corrections) == 12 * sizeof(double),
                    "gather_forces reads vectors, spring ends and corrections as packed data");
      gathered = true;
#pragma omp parallel num_threads(ctx_.threads) reduction(max : max_r2) if (ctx_.threads > 1)
      {
        int lo, hi, t;
        my_share(n, lo, hi, t);
        lanes::NodeForces g;
        g.inc_e_off = ctx_.inc_e_off.data(), g.inc_e = ctx_.inc_e.data(), g.inc_b_off = ctx_.inc_b_off.data();
        g.inc_b = reinterpret_cast<const char*>(ctx_.inc_b.data());
        g.elem_force = s_.elem_force.empty() ? nullptr : s_.elem_force[0].data();
        g.bend_force = s_.bend_force.empty() ? nullptr : s_.bend_force[0].data();
        g.inv_mass = model_.inv_mass.data(), g.fixed = model_.fixed.data(), g.dt = model_.dt;
        g.f = s_.f[0].data(), g.v = s_.v[0].data(), g.x = s_.x[0].data(), g.v_prev = s_.v_prev[0].data();
        g.corr = s_.corr[0].dv_contact.data();
        g.lo = lo, g.hi = hi;
        max_r2 = lanes::gather_forces(g, max_r2);
      }
    }
  }
  if (!gathered) {
#pragma omp parallel for num_threads(ctx_.threads) schedule(static) reduction(max : max_r2) if (ctx_.threads > 1)
    for (int i = 0; i < n; ++i) {
      V3 f = V3::Zero();
      // (+1 F is F and -1 F is -F exactly, and f + (-F) is f - F: the same sums as weighing each
      // element force by its sign, without the multiplications)
      auto element = [&](int k) {
        const int c = ctx_.inc_e[k];
        if (c >= 0)
          f += s_.elem_force[c];
        else
          f -= s_.elem_force[~c];
      };
      auto spring = [&](int k) { f += ctx_.inc_b[k].second * s_.bend_force[ctx_.inc_b[k].first]; };
      const int e0 = ctx_.inc_e_off[i], ne_i = ctx_.inc_e_off[i + 1] - e0;
      const int b0 = ctx_.inc_b_off[i], nb_i = ctx_.inc_b_off[i + 1] - b0;
      // A node inside one yarn (2 elements, 2 spring ends) or, pin-jointed, inside two (4 and
      // 4): the same terms in the same order, unrolled (the loops' control was a third of it).
      if (ne_i == 2 && nb_i == 2) {
        element(e0), element(e0 + 1), spring(b0), spring(b0 + 1);
      } else if (ne_i == 4 && nb_i == 4) {
        element(e0), element(e0 + 1), element(e0 + 2), element(e0 + 3);
        spring(b0), spring(b0 + 1), spring(b0 + 2), spring(b0 + 3);
      } else {
        for (int k = e0; k < e0 + ne_i; ++k) element(k);
        for (int k = b0; k < b0 + nb_i; ++k) spring(k);
      }
      s_.f[i] = f;
      max_r2 = std::max(max_r2, free_update(model_, s_, i, f));
    }
  }
  ctx_.max_r2 = max_r2;
  s_.book.stored_now = stored + bend_stored;
  s_.book.damping_cum += damp;
  s_.book.viscous_cum += diss;
  for (double& h : s_.grip_heat) s_.book.clamp_cum += std::exchange(h, 0.0);  // (in clamp order: any thread count)
  s_.book.released_cum += released + bend_released;
  run_.max_strain = max_strain;
}

}  // namespace

template <class Real>
void internal_forces(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx) {
  InternalForces<Real>{model, s, run, ctx}.run();
}

// The two precisions (solver.h: Precision).
template void internal_forces(const Model&, State<float>&, RunState&, Context<float>&);
template void internal_forces(const Model&, State<double>&, RunState&, Context<double>&);

}  // namespace ravel::detail

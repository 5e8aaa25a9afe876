// SolverT<Real>: the stages named in solver.h, in single or double precision.
#include "solver.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>

#include "contact_lanes.h"
#include "element_lanes.h"
#include "geometry.h"
#include "material.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace ravel {

std::uint64_t Solver::state_hash() const {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a over the raw bytes of the state
  hash_into(h);
  return h;
}

namespace {

inline void fnv(std::uint64_t& h, const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
}

template <class Real>
class SolverT final : public Solver {
 public:
  using V3 = Eigen::Matrix<Real, 3, 1>;

  SolverT(const Model& m, int threads)
      : Solver(m),
        zener_(ZenerConstants{m.k1 > 0 ? m.k1 : 1, m.k2 > 0 ? m.k2 : 1, m.damping > 0 ? m.damping : 1}, m.dt) {
    const int n = model_.node_count, ne = model_.element_count;
    x_.resize(n);
    v_.resize(n);
    f_.resize(n);
    v_prev_.assign(n, V3::Zero());
    dv_contact_.assign(n, V3::Zero());
    dv_friction_.assign(n, V3::Zero());
    compressible_ = model_.compression != CrossingCompression::rigid;
    if (compressible_) {
      dv_compress_.assign(n, V3::Zero());
      sum_c_.assign(n, V3::Zero());
    }
    dv_pfriction_.assign(n, V3::Zero());
    dx_contact_.assign(n, V3::Zero());
    held_n_.assign(n, V3::Zero());
    held_flag_.assign(n, 0);
    sum_n_.assign(n, V3::Zero());
    sum_f_.assign(n, V3::Zero());
    sum_s_.assign(n, V3::Zero());
    held_imp_.assign(n, V3::Zero());
    held_fric_.assign(n, V3::Zero());
    held_comp_.assign(n, V3::Zero());
    for (int i = 0; i < n; ++i) {
      x_[i] = model_.x0[i].template cast<Real>();
      v_[i].setZero();
      f_[i].setZero();
    }
    strain_.assign(ne, Real(0));
    prev_strain_.assign(ne, Real(0));
    ev_.assign(ne, Real(0));
    stress_.assign(ne, Real(0));
    crimp_damp_stress_.assign(crimp_damping_k_ > 0 ? ne : 0, Real(0));
    broken_flag_.assign(ne, 0);
    elem_force_.assign(ne, V3::Zero());
    elem_energy_.assign(ne, 0.0);
    bend_force_.assign(model_.bend_k.size(), V3::Zero());
    for (int e = 0; e < ne; ++e) {
      // Initial strain (slack for the straight-chord models).
      const Real len = (x_[model_.elem_b[e]] - x_[model_.elem_a[e]]).norm();
      Real eps = len / Real(model_.elem_rest[e]) - Real(1), mat = eps,
           dg = Real(1);  // (eps: the yarn's own strain after crimp_stage)
      if (model_.crimp_strain > 0) crimp_stage(eps, mat, dg);
      strain_[e] = eps;
      prev_strain_[e] = mat;
    }
    build_incidence();
    const int nc = int(model_.crossings.size());
    cr_kw_.resize(nc);
    cr_kf_.resize(nc);
    cr_win_.assign(nc, WindowIds{});
    cr_stick_w_.assign(nc, -1.0);
    cr_stick_f_.assign(nc, -1.0);
    cr_active_.assign(nc, 1);
    cr_fn_.assign(nc, 0.0);
    cr_ft_.assign(nc, 0.0);
    cr_slip_.assign(nc, 0.0);
    cr_gap_.assign(nc, 0.0);
    cr_sliding_.assign(nc, 0);
    cr_event_.assign(nc, 0);
    cr_fn_step_.assign(nc, 0.0);
    cr_u_.assign(nc, 0.0);
    cr_stick_e_.assign(nc, 0.0);
    cr_last_.resize(nc);
    for (int c = 0; c < nc; ++c) {
      cr_kw_[c] = model_.crossings[c].warp_node;
      cr_kf_[c] = model_.crossings[c].weft_node;
      cr_last_[c] = {cr_kw_[c], cr_kf_[c], pair_offset(c, cr_kw_[c], cr_kf_[c])};
    }
    xp_ = model_.projectile_x0.cast<Real>();
    vp_ = (model_.impact_velocity * model_.flight_dir).template cast<Real>();
    set_threads(threads);
    // Initial ledger: all energy is the projectile's.
    ke_half_ = 0.5 * model_.projectile_mass * double(vp_.squaredNorm());
    ledger_.projectile_ke_J = ke_half_;
    escape_radius2_ = std::pow(10.0 * (model_.half_width + model_.half_length) + 1.0, 2);
  }

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
    if (!divergence_.empty()) return;
    internal_forces();                              // Eq 3, 23: element stress from strain; bending; failure
    close_ledger_row();                             // ledger at t - dt/2
    integrate();                                    // Eq 1-2
    projectile_contact();                           // Eq 18-22
    if (!model_.crossings.empty()) yarn_contact();  // Eq 5-17
    release_held();                                 // the yarn contact's push on held nodes -> projectile
    if (!model_.crossings.empty() && steps_ % kPenetrationCheckEvery == 0) residual_penetration();
    finish_step();
  }

  Vec3d projectile_position() const override {
    return xp_.template cast<double>();
  }
  Vec3d projectile_velocity() const override {
    return vp_.template cast<double>();
  }
  Vec3d position(int i) const override {
    return x_[i].template cast<double>();
  }
  Vec3d velocity(int i) const override {
    return v_[i].template cast<double>();
  }
  void set_velocity(int i, const Vec3d& v) override {
    v_[i] = v.cast<Real>();
  }
  void set_position(int i, const Vec3d& x) override {
    x_[i] = x.cast<Real>();
  }
  void set_projectile_velocity(const Vec3d& v) override {
    vp_ = v.cast<Real>();
    ke_half_ = fabric_ke() + 0.5 * model_.projectile_mass * double(vp_.squaredNorm());
  }
  void set_projectile_position(const Vec3d& x) override {
    xp_ = x.cast<Real>();
  }
  void set_external_force(int node, const Vec3d& f) override {
    for (auto& e : f_ext_)
      if (e.first == node) {
        e.second = f.cast<Real>();
        return;
      }
    f_ext_.push_back({node, f.cast<Real>()});
  }
  double strain(int e) const override {
    return double(strain_[e]);
  }
  double stress(int e) const override {
    return double(stress_[e]);
  }
  bool broken(int e) const override {
    return broken_flag_[e] != 0;
  }
  bool crossing_active(int c) const override {
    return cr_active_[c] != 0;
  }
  bool crossing_sliding(int c) const override {
    return cr_sliding_[c] != 0;
  }
  double crossing_normal_force(int c) const override {
    return cr_fn_[c];
  }
  double crossing_friction_force(int c) const override {
    return cr_ft_[c];
  }
  double crossing_slip_rate(int c) const override {
    return cr_slip_[c];
  }
  double crossing_gap(int c) const override {
    return cr_gap_[c];
  }
  int crossing_warp_node(int c) const override {
    return cr_kw_[c];
  }
  int crossing_weft_node(int c) const override {
    return cr_kf_[c];
  }

 protected:
  void save_state(StateWriter& w) const override {
    const_cast<SolverT*>(this)->state_io(w);
  }
  void load_state(StateReader& r) override {
    state_io(r);
  }

  // Every member a step carries to the next, in one list for writing and reading (the
  // per-step scratch is included where a later step or the ledger reads it). What the
  // model and the thread count determine is rebuilt by the constructor, not written.
  template <class Ar>
  void state_io(Ar& ar) {
    base_io(ar);
    ar.mark(0x52565331);  // "RVS1"
    ar.vec(x_);
    ar.vec(v_);
    ar.vec(f_);
    ar.vec(v_prev_);
    ar.vec(dv_contact_);
    ar.vec(dv_friction_);
    ar.vec(dv_pfriction_);
    ar.vec(dx_contact_);
    ar.vec(dv_compress_);
    ar.vec(sum_c_);
    ar.vec(cr_u_);
    ar.vec(cr_stick_e_);
    ar.pod(stick_end_);
    ar.pod(stick_prev_);
    ar.pod(friction_work_cum_);
    ar.pod(compress_end_);
    ar.pod(compress_prev_);
    ar.pod(compress_work_cum_);
    ar.vec(held_n_);
    ar.vec(held_imp_);
    ar.vec(held_fric_);
    ar.vec(held_comp_);
    ar.vec(held_list_);
    ar.vec(ptouch_list_);
    ar.vec(held_flag_);
    ar.vec(sum_n_);
    ar.vec(sum_f_);
    ar.vec(sum_s_);
    ar.pod(proj_impulse_);
    ar.vec(strain_);
    ar.vec(prev_strain_);
    ar.vec(ev_);
    ar.vec(stress_);
    ar.vec(broken_flag_);
    ar.vec(elem_force_);
    ar.vec(bend_force_);
    ar.vec(elem_energy_);
    ar.vec(cr_kw_);
    ar.vec(cr_kf_);
    ar.vec(cr_win_);
    ar.vec(cr_stick_w_);
    ar.vec(cr_stick_f_);
    ar.vec(cr_fn_);
    ar.vec(cr_ft_);
    ar.vec(cr_slip_);
    ar.vec(cr_gap_);
    ar.vec(cr_fn_step_);
    ar.vec(cr_last_);
    ar.vec(cr_active_);
    ar.vec(cr_sliding_);
    ar.vec(cr_event_);
    ar.pod(xp_);
    ar.pod(vp_);
    ar.pod(ke_half_);
    ar.pod(ke_fabric_half_);
    ar.pod(stored_now_);
    ar.pod(stored_prev_);
    ar.pod(viscous_cum_);
    ar.pod(viscous_prev_);
    ar.pod(released_cum_);
    ar.pod(released_prev_);
    ar.pod(pfriction_cum_);
    ar.pod(contact_cum_);
    ar.pod(external_cum_);
    ar.pod(shift_cum_);
    ar.vec(shifted_);
    ar.vec(elem_mark_);
    ar.vec(bend_mark_);
    ar.pod(mark_);
    ar.vec(f_ext_);
    ar.vec(crimp_damp_stress_);
    ar.pod(damping_cum_);
    ar.pod(balance_window_);  // the slow-drift check's memory (close_ledger_row)
    ar.mark(0x52564532);      // "RVE2"
  }

  void hash_into(std::uint64_t& h) const override {
    fnv(h, x_.data(), x_.size() * sizeof(V3));
    fnv(h, v_.data(), v_.size() * sizeof(V3));
    fnv(h, ev_.data(), ev_.size() * sizeof(Real));
    fnv(h, broken_flag_.data(), broken_flag_.size());
    fnv(h, cr_stick_w_.data(), cr_stick_w_.size() * sizeof(double));
    fnv(h, cr_stick_f_.data(), cr_stick_f_.size() * sizeof(double));
    fnv(h, xp_.data(), sizeof(V3));
    fnv(h, vp_.data(), sizeof(V3));
  }

 private:
  // ---------------------------------------------------------------- set-up
  // Node -> (element, sign) and node -> (bending spring, weight) lists, so forces are
  // gathered per node: race-free in parallel and independent of the thread count.
  void build_incidence() {
    const int n = model_.node_count;
    std::vector<std::vector<std::pair<int, Real>>> ne(n), nb(n);
    for (int e = 0; e < model_.element_count; ++e) {
      ne[model_.elem_b[e]].push_back({e, Real(1)});  // element force acts on b, -force on a
      ne[model_.elem_a[e]].push_back({e, Real(-1)});
    }
    for (size_t s = 0; s < model_.bend_k.size(); ++s) {
      // Spring pushes midpoint 2 by +F and midpoint 1 by -F; half to each end node.
      const int e1 = model_.bend_e1[s], e2 = model_.bend_e2[s];
      if (model_.bend_mirror[s] >= 0) {
        // Mirror spring: bend_force_ is the force on this element's midpoint.
        nb[model_.elem_a[e1]].push_back({int(s), Real(0.5)});
        nb[model_.elem_b[e1]].push_back({int(s), Real(0.5)});
        continue;
      }
      // Adjoining elements share a node, which gets -F/2 and +F/2 of the same spring: no
      // force, and no entry (adding and taking away the same half would only round).
      const int ends[4] = {model_.elem_a[e1], model_.elem_b[e1], model_.elem_a[e2], model_.elem_b[e2]};
      for (int k = 0; k < 4; ++k) {
        const bool shared =
            (k < 2 ? (ends[k] == ends[2] || ends[k] == ends[3]) : (ends[k] == ends[0] || ends[k] == ends[1]));
        if (!shared) nb[ends[k]].push_back({int(s), Real(k < 2 ? -0.5 : 0.5)});
      }
    }
    inc_e_off_.assign(n + 1, 0);
    inc_b_off_.assign(n + 1, 0);
    for (int i = 0; i < n; ++i) {
      inc_e_off_[i + 1] = inc_e_off_[i] + int(ne[i].size());
      inc_b_off_[i + 1] = inc_b_off_[i] + int(nb[i].size());
      for (auto& p : ne[i]) inc_e_.push_back(p);
      for (auto& p : nb[i]) inc_b_.push_back(p);
    }
  }

  // One element's strain, stress update, failure and force (the one-element code the lanes mirror).
  // Returns whether the element failed in this step.
  bool element_one(int e, bool zener, double E, double fail, bool breakable, double& stored, double& diss,
                   double& released, double& max_strain, double& damp) {
    if (broken_flag_[e]) {
      elem_force_[e].setZero();
      return false;
    }
    const V3 dx = x_[model_.elem_b[e]] - x_[model_.elem_a[e]];
    const Real len = dx.norm();
    const double rest = model_.elem_rest[e];
    Real eps = len / Real(rest) - Real(1);
    const double vol = model_.elem_area[e] * rest;
    // The yarn law's strain (the crimp stage's material strain for the pin-jointed model),
    // and the force factor d(material strain)/d(strain): a crimped element's force is
    // sigma A g'(e), the derivative of its stored energy.
    Real mat = eps, dg = Real(1);
    const double apparent = double(eps);  // against L0 (crimp_stage turns eps into the yarn's own strain)
    if (model_.crimp_strain > 0) crimp_stage(eps, mat, dg);
    const double mat_prev = double(prev_strain_[e]);
    double sig, u, dd = 0;
    if (zener) {
      const ZenerStep zs = zener_.step(double(prev_strain_[e]), double(mat), double(ev_[e]));
      ev_[e] = Real(zs.ev);
      sig = zs.stress;
      u = zener_stored(zener_.c, sig, zs.ev) * vol;
      dd = zs.dissipated * vol;
    } else {
      sig = mat > 0 ? E * double(mat) : 0.0;
      u = sig * sig / (2 * E) * vol;
    }
    // Snap damping (solver.snap_damping, docs/MODEL.md §3): in the step a slack element turns
    // taut its stress gains beta E_inst times its strain rate, never below zero; the work is
    // booked as damping_J. Elements that stay taut (the waves) are not damped.
    double sig_total = sig;
    if (sig > 0 && damping_k_ > 0 && stress_[e] == Real(0)) {
      const double de = double(mat) - mat_prev;
      sig_total = std::max(0.0, sig + damping_k_ * de * zener_.inv_dt);
      damp += (sig_total - sig) * de * vol;
    }
    // Crimp damping (yarn.crimp_damping, pin-jointed only, docs/MODEL.md §1): a taut element's
    // force gains beta E A times its apparent strain rate, never below zero. It damps the
    // lattice ringing a soft-then-stiff crimp stage radiates behind a steep front; slower waves
    // are damped in proportion to their frequency. Its work is booked as damping_J, over each
    // step's stretch at the mean of the damping stress at its two ends (the trapezoid; booking
    // the end-of-step stress alone made the ledger error first order in dt).
    double sig_force = sig_total * double(dg);
    if (crimp_damping_k_ > 0) {
      // strain_[e] still holds last step's own strain: its apparent strain a step ago.
      const double de = apparent - ((1 + double(strain_[e])) * (1 + model_.crimp_strain) - 1);
      double extra = 0;
      if (sig > 0) {
        const double f = std::max(0.0, sig_force + crimp_damping_k_ * de * zener_.inv_dt);
        extra = f - sig_force;
        sig_force = f;
      }
      damp += 0.5 * (double(crimp_damp_stress_[e]) + extra) * de * vol;
      crimp_damp_stress_[e] = Real(extra);
    }
    prev_strain_[e] = mat;
    strain_[e] = eps;
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
      broken_flag_[e] = 1;
      released += elem_energy_[e] + 0.5 * double(stress_[e]) * vol * (double(mat) - mat_prev);
      stress_[e] = 0;
      if (crimp_damping_k_ > 0) crimp_damp_stress_[e] = 0;
      elem_force_[e].setZero();
      return true;
    }
    elem_energy_[e] = u;
    stored += u;
    stress_[e] = Real(sig_total);
    max_strain = std::max(max_strain, double(eps));
    // Force on node b: -sigma A along the element (pulls b towards a).
    elem_force_[e] = len > Real(0) ? V3(dx * Real(-sig_force * model_.elem_area[e] / double(len))) : V3::Zero();
    return false;
  }

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

  // ---------------------------------------------------------------- stages
  // Element strain from positions, constitutive update, failure, element force vectors,
  // bending springs, then gather into nodal forces.
  void internal_forces() {
    const int ne = model_.element_count;
    const bool zener = model_.material == Material::zener;
    const double E = model_.modulus_inst;
    const double fail = model_.failure_strain;
    const bool breakable = model_.breakable;
    double stored = 0, diss = 0, released = 0, max_strain = 0, damp = 0;
    int newly_broken[2] = {0, 0}, nbroke = 0;
    // Elements in groups of four: intact groups of a Zener yarn in which nothing fails go
    // through the lanes (the same numbers; element_lanes.h), the rest one at a time. Sums are
    // taken in element order either way.
    const bool use_lanes = zener && lanes_on() && model_.crimp_strain == 0;
    const int ng = (ne + kBatch - 1) / kBatch;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : stored, diss, released, nbroke, damp) \
    reduction(max : max_strain) if (threads_ > 1)
    for (int grp = 0; grp < ng; ++grp) {
      const int e0 = grp * kBatch, e1 = std::min(ne, e0 + kBatch);
      if constexpr (std::is_same_v<Real, double>) {
        bool intact = use_lanes && e1 - e0 == kBatch;
        for (int e = e0; e < e1 && intact; ++e) intact = !broken_flag_[e];
        if (intact) {
          lanes::ElementBatch b;
          b.x = x_[0].data();
          b.a = &model_.elem_a[e0];
          b.b = &model_.elem_b[e0];
          b.rest = &model_.elem_rest[e0];
          b.area = &model_.elem_area[e0];
          b.k1 = zener_.c.k1, b.k2 = zener_.c.k2, b.mu = zener_.c.mu;
          b.dt = zener_.dt, b.inv_dt = zener_.inv_dt, b.lam = zener_.lam, b.g = zener_.g;
          b.decay = zener_.decay, b.slack_decay = zener_.slack_decay;
          b.fail = fail;
          b.breakable = breakable;
          b.damping_k = damping_k_;
          b.prev_strain = &prev_strain_[e0];
          b.ev = &ev_[e0];
          b.strain = &strain_[e0];
          b.stress = &stress_[e0];
          b.energy = &elem_energy_[e0];
          b.force = elem_force_[e0].data();
          if (lanes::zener4(b)) {
            for (int l = 0; l < kBatch; ++l) {
              diss += b.dd[l];
              damp += b.dw[l];
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
    // Count failures serially to keep the count per family (only in a step with one).
    for (int e = 0; e < ne && nbroke > 0; ++e) {
      if (broken_flag_[e] == 1) {
        broken_flag_[e] = 2;
        newly_broken[model_.yarn_family[model_.elem_yarn[e]]]++;
      }
    }
    broken_[0] += newly_broken[0];
    broken_[1] += newly_broken[1];
    // Bending: compression-only springs between midpoints of adjoining elements.
    const int nbend = int(model_.bend_k.size());
    double bend_stored = 0;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : bend_stored) if (threads_ > 1)
    for (int s = 0; s < nbend; ++s) {
      const int e1 = model_.bend_e1[s], e2 = model_.bend_e2[s];
      if (broken_flag_[e1] || broken_flag_[e2]) {
        bend_force_[s].setZero();
        continue;
      }
      const int ax = model_.bend_mirror[s];
      if (ax >= 0) {
        // Against the mirror image: midpoint distance 2 |M_ax|; pushes M away from the
        // plane. Half of the spring's energy belongs to this side of the plane.
        const Real mc = Real(0.5) * (x_[model_.elem_a[e1]][ax] + x_[model_.elem_b[e1]][ax]);
        const double comp = model_.bend_rest[s] - 2 * std::abs(double(mc));
        bend_force_[s].setZero();
        if (comp > 0) {
          bend_stored += 0.25 * model_.bend_k[s] * comp * comp;
          bend_force_[s][ax] = Real(mc >= Real(0) ? 1 : -1) * Real(model_.bend_k[s] * comp);
        }
        continue;
      }
      const V3 m1 = Real(0.5) * (x_[model_.elem_a[e1]] + x_[model_.elem_b[e1]]);
      const V3 m2 = Real(0.5) * (x_[model_.elem_a[e2]] + x_[model_.elem_b[e2]]);
      const V3 d = m2 - m1;
      const Real len = d.norm();
      const double r = model_.bend_rest[s], k = model_.bend_k[s], sl = double(len);
      if (sl >= r) {
        bend_force_[s].setZero();
        continue;
      }
      // Compression-only spring 1/2 k (r - s)^2, pushing midpoint 2 away from 1. Below
      // s = r/2 (a yarn folded back on itself, e.g. a broken end whipping) the potential
      // continues as k r^2/4 - k s^2/2, whose force k d stays smooth through s = 0, where
      // the cone of 1/2 k (r - s)^2 would flip direction from one step to the next.
      if (sl >= 0.5 * r) {
        bend_stored += 0.5 * k * (r - sl) * (r - sl);
        bend_force_[s] = d * Real(k * (r - sl) / sl);
      } else {
        bend_stored += 0.25 * k * r * r - 0.5 * k * sl * sl;
        bend_force_[s] = d * Real(k);
      }
    }
    // Gather.
    const int n = model_.node_count;
#pragma omp parallel for num_threads(threads_) schedule(static) if (threads_ > 1)
    for (int i = 0; i < n; ++i) {
      V3 f = V3::Zero();
      for (int k = inc_e_off_[i]; k < inc_e_off_[i + 1]; ++k) f += inc_e_[k].second * elem_force_[inc_e_[k].first];
      for (int k = inc_b_off_[i]; k < inc_b_off_[i + 1]; ++k) f += inc_b_[k].second * bend_force_[inc_b_[k].first];
      f_[i] = f;
    }
    stored_now_ = stored + bend_stored;
    damping_cum_ += damp;
    viscous_cum_ += diss;
    released_cum_ += released;
    max_strain_ = max_strain;
  }

  // The ledger at t - dt/2 (see the header comment): kinetic energy of v(t - dt/2), the
  // mean of stored / cumulative-dissipation values at t - dt and t.
  void close_ledger_row() {
    if (steps_ == 0) {
      compress_prev_ = compress_end_;
      stick_prev_ = stick_end_;
      stored_prev_ = stored_now_;
      viscous_prev_ = viscous_cum_;
      released_prev_ = released_cum_;
      return;
    }
    Ledger& l = ledger_;
    l.fabric_ke_J = ke_fabric_half_;
    l.projectile_ke_J = ke_half_ - ke_fabric_half_;
    l.strain_energy_J = 0.5 * (stored_prev_ + stored_now_);
    l.viscous_J = 0.5 * (viscous_prev_ + viscous_cum_);
    l.damping_J = damping_cum_;
    l.released_J = 0.5 * (released_prev_ + released_cum_);
    // Dissipated by friction: the work its impulses took from the yarns (and the projectile)
    // less what the stick penalty springs hold (Eq 12: a stuck contact stores K/2 e^2 and
    // gives it back; only the rest is lost).
    l.projectile_friction_J = pfriction_cum_;
    l.contact_loss_J = contact_cum_;
    l.shift_work_J = shift_cum_;
    l.compression_J = 0.5 * (compress_prev_ + compress_end_);
    l.stick_energy_J = 0.5 * (stick_prev_ + stick_end_);
    l.friction_work_J = 0.0 - (friction_work_cum_ + l.stick_energy_J);  // (0.0 - : no negative zero)
    l.compression_loss_J = -compress_work_cum_ - l.compression_J;
    l.external_work_J = external_cum_;
    stored_prev_ = stored_now_;
    viscous_prev_ = viscous_cum_;
    released_prev_ = released_cum_;
    compress_prev_ = compress_end_;
    stick_prev_ = stick_end_;
    const double e0 = 0.5 * model_.projectile_mass * model_.impact_velocity * model_.impact_velocity;
    const double total = l.total();
    if (!std::isfinite(total)) {
      fail("non_finite", "the energy ledger became NaN/infinite (a node or element went non-finite)");
    } else if (e0 > 0) {
      // Every ledger term is computed from its own mechanism, so a ledger that no longer
      // adds up to the initial energy means the integration has gone wrong. Two ways:
      // unstable modes feeding energy in (fast: within a few hundred steps; tension-only
      // yarns then shed it by breaking, so it never blows up), or the slow drift of a long
      // run with hundreds of breaks at a coarse step (it vanishes as dt is lowered). The
      // first stops the run; the second is a warning until it reaches 4x the limit.
      const double err = std::abs(total - e0) / e0;
      if (steps_ % kBalanceWindow == 0) {
        balance_window_[(steps_ / kBalanceWindow) % 8] = err;
      }
      const double earlier = balance_window_[(steps_ / kBalanceWindow + 1) % 8];  // ~8 windows ago
      const double recent = balance_window_[(steps_ / kBalanceWindow) % 8];       // this window's start
      // Half the limit gained within one window (64 steps) is an instability even below the
      // limit itself: a mode growing that fast breaks the yarns it runs in before the ledger
      // reaches the limit (a pin-jointed patch at dt_factor 2 tore apart in 32 steps with 4.4 %
      // created).
      const bool jumped = err - recent > 0.5 * max_balance_error_;
      const bool fast = jumped || err - earlier > 0.5 * max_balance_error_ || err > 4 * max_balance_error_;
      if (err > max_balance_error_ || jumped) {
        if (fast) {
          fail("energy_balance", "the energy ledger is off by " + fmt(100 * (total - e0) / e0) +
                                     " % of the impact energy (energy " + (total > e0 ? "created" : "lost") +
                                     " without a mechanism): the explicit integration is unstable");
        } else if (!diag_.balance_drift) {
          diag_.balance_drift = true;
          diag_.balance_drift_time = time_;
        }
      }
    }
  }
  static constexpr long kBalanceWindow = 64;  // steps per window of the drift/instability test
  double balance_window_[8] = {0, 0, 0, 0, 0, 0, 0, 0};

  // Eq 1-2: v(t+dt/2) = v(t-dt/2) + dt/m f; x(t+dt) = x(t) + dt v(t+dt/2). Fixed velocity
  // components (clamps, symmetry planes) stay zero.
  void integrate() {
    const int n = model_.node_count;
    const Real dt = Real(model_.dt);
    double maxr2 = 0;

#pragma omp parallel for num_threads(threads_) schedule(static) reduction(max : maxr2) if (threads_ > 1)
    for (int i = 0; i < n; ++i) {
      v_prev_[i] = v_[i];
      dx_contact_[i].setZero();
      const std::uint8_t fx = model_.fixed[i];
      if (fx == fix_all) continue;
      V3 v = v_[i] + (dt * Real(model_.inv_mass[i])) * f_[i];
      if (fx) zero_fixed(v, fx);
      v_[i] = v;
      x_[i] += dt * v;
      maxr2 = std::max(maxr2, double(x_[i].squaredNorm()));
    }
    // External loads (rare: tests and pull-out): applied after the free update.
    for (const auto& [i, F] : f_ext_) {
      if (model_.fixed[i] == fix_all) continue;
      V3 dv = (dt * Real(model_.inv_mass[i])) * F;
      zero_fixed(dv, model_.fixed[i]);
      v_[i] += dv;
      x_[i] += dt * dv;
    }
    xp_ += dt * vp_;
    if (!std::isfinite(maxr2))
      fail("non_finite", "a yarn node position became NaN/infinite");
    else if (!(maxr2 < escape_radius2_))
      fail("node_escaped", "a yarn node escaped the domain (more than 10 fabric sizes from the centre)");
  }

  // Zero the components of a node's velocity / displacement change along its fixed axes
  // (clamps, symmetry planes).
  static void zero_fixed(V3& v, std::uint8_t fx) {
    if (fx & fix_x) v.x() = 0;
    if (fx & fix_y) v.y() = 0;
    if (fx & fix_z) v.z() = 0;
  }

  // ------------------------------------------------------------ yarn contact (Eq 5-17)
  int ynode(int yarn, int k) const {
    return model_.yarn_node(yarn, k);
  }
  bool seg_ok(int yarn, int s) const {
    return s >= 0 && s + 1 < model_.yarn_size(yarn) && !broken_flag_[model_.yarn_elem_offset[yarn] + s];
  }
  Real seg_len(int yarn, int s) const {
    return (x_[ynode(yarn, s + 1)] - x_[ynode(yarn, s)]).norm();
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

  // Arc length along a yarn from material coordinate u0 to u1 (coordinate = segment + fraction).
  Real arc_between(int yarn, double u0, double u1, const KnownLengths& known = {}) const {
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
  double advance(int yarn, double u, double arc, const KnownLengths& known = {}) const {
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
  // The window's node ids around a tracked pair: what a window is loaded from. Each
  // crossing keeps those of its tracked pair (cr_win_), rebuilt when the pair moves.
  struct WindowIds {
    // The tracked pair these are for (none yet).
    int kw = std::numeric_limits<int>::min(), kf = 0;
    int node[6];          // warp kw-1..kw+1, weft kf-1..kf+1 (-1: past a yarn's end)
    int wseg0, fseg0;     // element index of warp segment kw-1 and weft segment kf-1
    std::uint8_t exists;  // bits 0, 1: warp segments kw-1, kw exist; 2, 3: weft kf-1, kf
  };
  WindowIds window_ids(const Crossing& cr, int kw, int kf) const {
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
  void load_window(const WindowIds& id, Window& w) const {
    w.kw = id.kw;
    w.kf = id.kf;
    for (int k = 0; k < 3; ++k) {
      w.wnode[k] = id.node[k];
      w.fnode[k] = id.node[3 + k];
      if (w.wnode[k] >= 0) w.xw[k] = x_[w.wnode[k]];
      if (w.fnode[k] >= 0) w.xf[k] = x_[w.fnode[k]];
    }
    for (int k = 0; k < 2; ++k) {
      w.wseg[k] = (id.exists >> k & 1) && !broken_flag_[id.wseg0 + k];
      w.fseg[k] = (id.exists >> (2 + k) & 1) && !broken_flag_[id.fseg0 + k];
    }
  }
  // The window of crossing c around its tracked pair.
  void load_window(int c, Window& w) {
    WindowIds& id = cr_win_[c];
    if (id.kw != cr_kw_[c] || id.kf != cr_kf_[c]) id = window_ids(model_.crossings[c], cr_kw_[c], cr_kf_[c]);
    load_window(id, w);
  }
  void load_window(const Crossing& cr, int kw, int kf, Window& w) const {
    load_window(window_ids(cr, kw, kf), w);
  }

  // Nearest node pair tracking: search the 3 x 3 neighbours (paper Fig. 2). A move at the
  // edge of the window is searched once more; moving again means the yarns slid more than
  // one node in one step, which the method assumes never happens: reported, not hidden.
  // Returns true in that case; `w` is left loaded around the tracked pair.
  bool track(int c, Window& w, bool loaded = false) {
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
      cr_kw_[c] += bw - 1;
      cr_kf_[c] += bf - 1;
      if (round >= 1) skipped = true;
      load_window(cr, cr_kw_[c], cr_kf_[c], w);
    }
    return skipped;
  }

  void release(int c, std::uint8_t why) {
    cr_active_[c] = 0;
    cr_stick_e_[c] = 0;  // the penalty spring lets go (its energy then shows as friction work)
    cr_fn_[c] = cr_ft_[c] = cr_slip_[c] = 0;
    cr_sliding_[c] = 0;
    cr_event_[c] |= why;
  }

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

  ContactGeom closest(const Crossing& cr, const Window& w) const {
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

  // Cross product of the first closest pair's warp and weft segments; times the crossing's
  // fixed sign it is the side test's normal n (SPEC §4), unnormalised.
  static V3 pair_cross(const Window& w, const ContactGeom& g) {
    const V3 tw = w.xw[g.sw - w.kw + 2] - w.xw[g.sw - w.kw + 1];
    const V3 tf = w.xf[g.sf - w.kf + 2] - w.xf[g.sf - w.kf + 1];
    return tw.cross(tf);
  }

  // Is the contact point at an end of the yarn beyond which it has no segment, with the
  // partner lying beyond that end? Then the partner has slipped off (ravelled out).
  bool slipped_off(int yarn, int seg, Real frac, const V3& toward_partner) const {
    const bool at_end = frac >= Real(1) - Real(1e-6) && !seg_ok(yarn, seg + 1) &&
                        !(seg + 2 == model_.yarn_size(yarn) && !(model_.yarn_end_free[yarn] & 2));
    const bool at_start =
        frac <= Real(1e-6) && !seg_ok(yarn, seg - 1) && !(seg == 0 && !(model_.yarn_end_free[yarn] & 1));
    if (!at_end && !at_start) return false;
    const V3 t = x_[ynode(yarn, seg + 1)] - x_[ynode(yarn, seg)];
    const Real L = t.norm();
    if (L <= Real(0)) return false;
    const Real along = toward_partner.dot(t) / L;
    const Real dist = toward_partner.norm();
    return at_end ? along > Real(0.5) * dist : -along > Real(0.5) * dist;
  }

  // Material coordinate (node index + fraction) of point p along a yarn near node k:
  // projection on the chord joining k's neighbours (unit direction returned in `tangent`).
  double chord_coord(int yarn, int k, const V3* xs, const bool* seg, const V3& p, V3& tangent) const {
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
  void coord_nodes(int yarn, double u, int& n0, int& n1, Real& frac) const {
    const int s = std::clamp(floor_int(u), 0, model_.yarn_size(yarn) - 2);
    frac = Real(std::clamp(u - s, 0.0, 1.0));
    n0 = ynode(yarn, s);
    n1 = ynode(yarn, s + 1);
  }

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

  void yarn_contact() {
    const int nc = int(model_.crossings.size());
    const int N = model_.contact_iterations;
    impulses_.resize(nc);  // (cr_fn_step_, cr_ft_ and cr_event_ are cleared by each crossing's first pass)
    for (int pass = 1; pass <= N; ++pass) {
      // alpha_n = 1/sqrt(N - n + 1): the last pass applies the full remainder (SPEC §4).
      const Real alpha = Real(1.0 / std::sqrt(double(N - pass + 1)));
      const bool first = pass == 1, last = pass == N;
      if (threads_ > 1) {
        // Every crossing's corrections from the same state (Jacobi), then applied: each
        // thread owns a range of nodes and applies, in crossing order, the changes that
        // fall in its range: race-free, and the same sums whatever the number of threads.
        const int nb = (nc + kBatch - 1) / kBatch;
        rec_first_.resize(nc);
        rec_last_.resize(nc);
#pragma omp parallel for num_threads(threads_) schedule(static)
        for (int b = 0; b < nb; ++b) {
          const int c0 = b * kBatch, c1 = std::min(nc, (b + 1) * kBatch);
          crossing_batch(c0, c1, alpha, first, last, &impulses_[c0]);
          for (int c = c0; c < c1; ++c) {
            // The lowest and highest node the record can touch.
            const CrossingImpulse& r = impulses_[c];
            int a = std::numeric_limits<int>::max(), z = -1;
            auto take = [&](const int* nodes, int count) {
              for (int k = 0; k < count; ++k)
                if (nodes[k] >= 0) a = std::min(a, nodes[k]), z = std::max(z, nodes[k]);
            };
            if (r.has_n || r.has_s || r.has_c) take(r.node, 6);
            if (r.has_f) take(r.fnode, 4);
            rec_first_[c] = a;
            rec_last_[c] = z;
          }
        }
        // Running maximum of the highest node and running minimum (from the end) of the
        // lowest: a node range [lo, hi) is touched only by records between the first
        // crossing whose running maximum reaches lo and the last whose running minimum is
        // below hi. With the node numbering of model.cpp that is about 1/T of them each.
        for (int c = 1; c < nc; ++c) rec_last_[c] = std::max(rec_last_[c], rec_last_[c - 1]);
        for (int c = nc - 2; c >= 0; --c) rec_first_[c] = std::min(rec_first_[c], rec_first_[c + 1]);
#pragma omp parallel num_threads(threads_)
        {
          int lo, hi, t;
          my_share(model_.node_count, lo, hi, t);
          const int c_first = int(std::lower_bound(rec_last_.begin(), rec_last_.end(), lo) - rec_last_.begin());
          const int c_end = int(std::lower_bound(rec_first_.begin(), rec_first_.end(), hi) - rec_first_.begin());
          for (int c = c_first; c < c_end; ++c) gather(impulses_[c], lo, hi, kSums | kHeld);
          finish_pass(lo, hi);
        }
      } else {
        // One thread: the same sums, gathered as each crossing is done (nothing a crossing
        // reads changes until finish_pass). Held nodes take their corrections one by one,
        // which moves them: those wait until every crossing is done, then go in crossing order.
        held_records_.clear();
        CrossingImpulse rs[kBatch];
        for (int c0 = 0; c0 < nc; c0 += kBatch) {
          const int c1 = std::min(nc, c0 + kBatch);
          crossing_batch(c0, c1, alpha, first, last, rs);
          for (int c = c0; c < c1; ++c)
            if (gather(rs[c - c0], 0, model_.node_count, kSums)) held_records_.push_back(rs[c - c0]);
        }
        for (const CrossingImpulse& r : held_records_) gather(r, 0, model_.node_count, kHeld);
        finish_pass(0, model_.node_count);
      }
    }
    // Book what broke the method's assumptions, in crossing order; sum the normal forces and
    // count sliding and stuck crossings.
    double fsum = 0, usum = 0, esum = 0;
    int sliding = 0, stuck = 0;
    for (int c = 0; c < nc; ++c) {
      // How far the two yarns' material moved against each other this step: the offset of
      // last step's tracked node pair, then and now (the pair may have been re-chosen since).
      const LastPair was = cr_last_[c];
      const Real moved = (pair_offset(c, was.kw, was.kf) - was.offset).norm();
      cr_last_[c] = {cr_kw_[c], cr_kf_[c], pair_offset(c, cr_kw_[c], cr_kf_[c])};
      if (cr_active_[c]) {
        fsum += cr_fn_[c];
        usum += cr_u_[c];
        esum += cr_stick_e_[c];
        if (cr_fn_[c] > 0) (cr_sliding_[c] ? sliding : stuck)++;
        // Material slip: the stick point's advance, but never faster than the yarns move
        // against each other (a jump of the closest point along a kinked or re-paired
        // yarn is not slip).
        cr_slip_[c] = std::min(cr_slip_[c], double(moved) / double(model_.dt));
      }
      std::uint8_t ev = cr_event_[c];
      if (!ev) continue;
      const Crossing& cr = model_.crossings[c];
      auto note = [&](long& count, double& t, int& i, int& j) {
        if (count++ == 0) t = time_, i = cr.grid_i, j = cr.grid_j;
      };
      // A pair that moved more than one node while the yarns moved less than half a node
      // against each other was re-chosen by the changed shape (yarns folded, bunched or apart
      // near the projectile), not outrun: a smaller time step would not change it.
      if ((ev & ev_skip) && moved < Real(0.5) * Real(model_.elem_rest[model_.yarn_elem_offset[cr.warp_yarn]])) {
        ev &= std::uint8_t(~ev_skip);
        note(diag_.repaired, diag_.first_repair_time, diag_.first_repair_i, diag_.first_repair_j);
      }
      if (ev & ev_skip) note(diag_.skipped_nodes, diag_.first_skip_time, diag_.first_skip_i, diag_.first_skip_j);
      if (ev & ev_ravel) note(diag_.ravelled, diag_.first_ravel_time, diag_.first_ravel_i, diag_.first_ravel_j);
      if (ev & ev_lost) note(diag_.lost_segments, diag_.first_ravel_time, diag_.first_ravel_i, diag_.first_ravel_j);
      if (ev & ev_pass) note(diag_.passed_through, diag_.first_pass_time, diag_.first_pass_i, diag_.first_pass_j);
      if (ev & ev_separated) ++diag_.separated;
    }
    yarn_force_ = fsum;
    compress_end_ = usum;
    stick_end_ = esum;
    sliding_count_ = sliding;
    stuck_count_ = stuck;
  }

  // Gather one crossing's corrections of a pass for the nodes in [lo, hi): per node sums
  // (kSums), applied once per node by finish_pass; nodes the projectile holds take each
  // correction separately (kHeld), as the hold projects out the part pushing into the
  // projectile. Returns whether the record touches a held node.
  static constexpr int kSums = 1, kHeld = 2;
  bool gather(const CrossingImpulse& r, int lo, int hi, int what) {
    if (!r.any_held && (what & kSums)) {
      // The common case, no held node: every weight on a node in [lo, hi) goes to the sums.
      const unsigned span = unsigned(hi - lo);
      auto each = [lo, span](int count, const int* nodes, const Real* w, const V3 q, V3* __restrict sum) {
        for (int k = 0; k < count; ++k)
          if (unsigned(nodes[k] - lo) < span && w[k] != Real(0)) sum[nodes[k]] += w[k] * q;
      };
      if (r.has_n) each(6, r.node, r.w, r.P, sum_n_.data());
      if (r.has_f) each(4, r.fnode, r.fw, r.F, sum_f_.data());
      if (r.has_s) each(6, r.node, r.w, r.S, sum_s_.data());
      if (r.has_c) each(6, r.node, r.w, r.C, sum_c_.data());
      return false;
    }
    bool held = false;
    // One kind of correction: weights w on nodes, times the vector q.
    auto each = [&](int count, const int* nodes, const Real* w, const V3& q, std::vector<V3>& sum, auto&& take_held) {
      for (int k = 0; k < count; ++k) {
        const int i = nodes[k];
        if (unsigned(i - lo) >= unsigned(hi - lo) || w[k] == Real(0)) continue;  // i in [lo, hi), -1 not
        if (held_flag_[i]) {
          held = true;
          if (what & kHeld) take_held(i, w[k] * q);
        } else if (what & kSums) {
          sum[i] += w[k] * q;
        }
      }
    };
    if (r.has_n)
      each(6, r.node, r.w, r.P, sum_n_,
           [&](int i, const V3& p) { apply_impulse(i, p, &dv_contact_, r.hold, nullptr); });
    if (r.has_f)
      each(4, r.fnode, r.fw, r.F, sum_f_,
           [&](int i, const V3& p) { apply_impulse(i, p, &dv_friction_, r.hold, &held_fric_); });
    if (r.has_s) each(6, r.node, r.w, r.S, sum_s_, [&](int i, const V3& dx) { shift_node(i, dx, r.hold); });
    if (r.has_c)
      each(6, r.node, r.w, r.C, sum_c_,
           [&](int i, const V3& p) { apply_impulse(i, p, &dv_compress_, r.hold, &held_comp_); });
    return held;
  }

  // Apply the pass's gathered sums to the nodes in [lo, hi).
  void finish_pass(int lo, int hi) {
    const Real dt = Real(model_.dt);
    for (int i = lo; i < hi; ++i) {
      const Real im = Real(model_.inv_mass[i]);
      const std::uint8_t fx = model_.fixed[i];
      V3 dvn = im * sum_n_[i], dvf = im * sum_f_[i], dx = im * sum_s_[i];
      sum_n_[i].setZero();
      sum_f_[i].setZero();
      sum_s_[i].setZero();
      if (fx) {
        zero_fixed(dvn, fx);
        zero_fixed(dvf, fx);
        zero_fixed(dx, fx);
      }
      V3 dv = dvn + dvf;
      if (compressible_) {
        V3 dvc = im * sum_c_[i];
        sum_c_[i].setZero();
        if (fx) zero_fixed(dvc, fx);
        dv += dvc;
        dv_compress_[i] += dvc;
      }
      v_[i] += dv;
      dv_contact_[i] += dvn;
      dv_friction_[i] += dvf;
      x_[i] += dt * dv + dx;
      dx_contact_[i] += dx;
    }
  }

  // `acc`: where the node's velocity change is summed for the ledger's work of this kind of
  // correction; `part`: per node, where the share passed to the projectile is also summed
  // (friction and compression, whose work on the projectile is their own; null: the normal
  // correction's).
  void apply_impulse(int i, V3 P, std::vector<V3>* acc, bool hold, std::vector<V3>* part) {
    const Real im = Real(model_.inv_mass[i]);
    if (im == Real(0)) return;
    const Real pn = P.dot(held_n_[i]);
    if (hold && pn < Real(0)) {
      // Held by the projectile: the part pushing into it passes to the projectile.
      held_imp_[i] += pn * held_n_[i];
      if (part) (*part)[i] += pn * held_n_[i];
      P -= pn * held_n_[i];
    }
    V3 dv = im * P;
    zero_fixed(dv, model_.fixed[i]);
    v_[i] += dv;
    if (acc) (*acc)[i] += dv;
    x_[i] += Real(model_.dt) * dv;  // the predicted position follows the velocity change (Eq 2)
  }

  // Move a node by a mass-weighted shift (no velocity change); recorded for the ledger.
  void shift_node(int i, const V3& S, bool hold) {
    const Real im = Real(model_.inv_mass[i]);
    if (im == Real(0)) return;
    V3 dx = im * S;
    const Real dn = dx.dot(held_n_[i]);
    if (hold && dn < Real(0)) dx -= dn * held_n_[i];  // not into the projectile that holds it
    zero_fixed(dx, model_.fixed[i]);
    x_[i] += dx;
    dx_contact_[i] += dx;
  }

  // Crossings [c0, c1) (at most kBatch) in one pass: tracking of each, then the closest
  // points of those whose four segments are intact together in lanes (when on and the
  // processor has them; the same numbers bit for bit), then the rest of each.
  static constexpr int kBatch = lanes::kWidth;
  bool lanes_on() const {
    return simd_;  // set_simd: asked for, double precision, and the processor has the lanes
  }
  // `first`: the step's first pass, which clears the crossings' per-step state.
  void crossing_batch(int c0, int c1, Real alpha, bool first, bool last, CrossingImpulse* out) {
    Window w[kBatch];
    ContactGeom g[kBatch];
    bool on[kBatch];
    bool tracked[kBatch];
    if (first) {
      for (int c = c0; c < c1; ++c) cr_fn_step_[c] = 0, cr_ft_[c] = 0, cr_event_[c] = 0, cr_u_[c] = 0;
    }
    for (int c = c0; c < c1; ++c) {
      const int k = c - c0;
      CrossingImpulse& r = out[k];
      r.has_n = r.has_f = r.has_s = r.has_c = r.hold = r.any_held = false;
      on[k] = cr_active_[c];
      tracked[k] = false;
      if (!on[k]) continue;
      load_window(c, w[k]);
      // Windows the lanes take are searched there (and here again only if the pair moves).
      if (lane_window(w[k])) continue;
      if (track(c, w[k], true)) cr_event_[c] |= ev_skip;
      tracked[k] = true;
    }
    lanes::ClosestBatch lb;
    closest_batch(c0, c1, on, w, g, lb);
    for (int c = c0; c < c1; ++c) {
      const int k = c - c0;
      if (!on[k] || tracked[k] || !g[k].moved) continue;
      // The nearest pair moved: the one-crossing search from here, then its closest points.
      if (track(c, w[k], true)) cr_event_[c] |= ev_skip;
      g[k] = closest(model_.crossings[c], w[k]);
    }
    // The rest of each crossing, in three stages over the batch: each stage is a chain of
    // square roots and divisions, and four independent chains side by side keep the
    // processor busy where one crossing at a time would wait on each (same operations).
    bool go[kBatch];
    FrictionSetup fs[kBatch];
    for (int c = c0; c < c1; ++c)
      go[c - c0] = on[c - c0] && pass_normal(c, alpha, last, w[c - c0], g[c - c0], lb, out[c - c0]);
    for (int c = c0; c < c1; ++c)
      if (go[c - c0]) friction_setup(c, w[c - c0], g[c - c0], lb, out[c - c0], fs[c - c0]);
    for (int c = c0; c < c1; ++c)
      if (go[c - c0]) pass_friction(c, alpha, last, fs[c - c0], out[c - c0]);
  }

  // Whether the lanes take a window: all four segments next to the tracked pair intact.
  bool lane_window(const Window& w) const {
    return lanes_on() && w.wseg[0] && w.wseg[1] && w.fseg[0] && w.fseg[1];
  }
  // The closest points of the crossings c in [c0, c1) with on[c - c0] set, from their loaded
  // windows: the lane windows together in lanes (when on and the processor has them; the
  // same numbers bit for bit), the others one at a time.
  void closest_batch(int c0, int c1, const bool* on, const Window* w, ContactGeom* g, lanes::ClosestBatch& lb) const {
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

  // Normal correction of one tracked crossing in one pass, given its window and closest
  // points. Returns whether the crossing goes on to friction (not released, not clamped).
  bool pass_normal(int c, Real alpha, bool last, const Window& w, const ContactGeom& g, const lanes::ClosestBatch& lb,
                   CrossingImpulse& r) {
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
      if (g.dist > D && cr_gap_[c] > 0) {
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
      if (!held_flag_[i]) {
        winv += wi;  // free = 1 exactly
        continue;
      }
      r.any_held = true;
      const Real un = u.dot(held_n_[i]);
      const Real free = r.w[k] * un < Real(0) ? Real(1) - un * un : Real(1);
      winv += wi * free;
    }
    r.hold = winv >= Real(kMinHeldMobility) * winv_free;
    if (!r.hold) winv = winv_free;
    if (winv <= Real(0)) return false;  // every node clamped
    // Transverse compression (docs/MODEL.md §4): between the rest distance D and the
    // flattened distance c_min the crossing is a compliant contact; below c_min it is the
    // paper's rigid one. Rigid crossings have c_min = D, and everything below is as before.
    const Real span = compressible_ ? D - Real(cr.flattened_distance) : Real(0);  // compressible distance D - c_min
    const Real floor_pen = delta - span;                                          // penetration below c_min
    const bool compliant = span > Real(0) && delta > Real(0);
    // With the split, the approach speed of the two contact points along u bounds the
    // velocity change a correction may make (see below).
    Real approach = 0;
    if (model_.split_penetration && (floor_pen > Real(0) || compliant)) {
      Real vrel = 0;
      for (int k = 0; k < 6; ++k)
        if (r.node[k] >= 0) vrel += r.w[k] * v_[r.node[k]].dot(u);
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
          // A compressible crossing's shift is capped (compressed_shift), but never so far that
          // more than kFloorLeft c_min of closure below the floor is left: the cap paces the
          // removal of closure, it must not let the yarns pass through each other.
          const Real left = Real(kFloorLeft) * Real(cr.flattened_distance);
          r.S = (alpha * (span > Real(0) ? std::max(compressed_shift(shift, D), shift - left) : shift) / winv) * u;
          r.has_s = true;
        }
      }
      P = alpha * dv / winv;
      r.P = P * u;
      r.has_n = P > Real(0);
    }
    if (compliant) compress(c, alpha, last, std::min(span, span - delta), span, winv, P, approach, u, r);
    cr_fn_step_[c] += double(P / dt);  // Eq 11
    if (last) cr_gap_[c] = double(g.dist - D);
    return true;
  }

  // The compliant part of a crossing's normal contact: c(f) = c_min + span / (1 + f / F_half)
  // taken implicitly, at the end of the correction. With s the distance above c_min, q the
  // relative displacement the impulse makes (q = kap (f - f_acc), kap = dt^2 winv) and f_acc the
  // normal force the crossing has already had this step:
  //   f_acc + (s - s_p) / kap = F_half (span / s - 1)
  //   s^2 + (kap (f_acc + F_half) - s_p) s - kap F_half span = 0,
  // whose positive root is taken. An implicit update is stable at any stiffness: as f grows
  // the law stiffens without bound (c -> c_min), and the explicit force of a prototype
  // chattered there. It dissipates (like the rigid correction it becomes at high force):
  // the work the impulse takes beyond the law's stored energy is booked as compression_loss.
  // s_p: distance above c_min after the rigid part (>= 0); P: the rigid part's impulse.
  void compress(int c, Real alpha, bool last, Real s_p, Real span, Real winv, Real P, Real approach, const V3& u,
                CrossingImpulse& r) {
    const Crossing& cr = model_.crossings[c];
    const double dt = model_.dt;
    const double kap = dt * dt * double(winv), Fh = cr.compression_force;
    const double f_acc = cr_fn_step_[c] + double(P) / dt, sp = std::max(0.0, double(s_p)), sz = double(span);
    const double b = kap * (f_acc + Fh) - sp, k4 = 4 * kap * Fh * sz;
    const double root = std::sqrt(b * b + k4);
    double s = b > 0 ? 0.5 * k4 / (b + root) : 0.5 * (root - b);  // the positive root, without cancellation
    double q = s - sp, qv = q;
    // The force may exceed last step's only by what stops this step's approach (the rigid
    // contact's force): a crossing loads at the pace its yarns press, and unloads elastically.
    // A closure beyond that was there before the step (a yarn end snapping in, a tracking
    // move, a neighbour's shift): as with rigid contact, it is removed by moving the nodes,
    // with the force capped and the distance the law's at that force.
    const double qv_max = kap * (cr_fn_[c] + double(approach) / (dt * double(winv)) - f_acc);
    if (model_.split_penetration && q > std::max(0.0, qv_max)) {
      qv = std::max(0.0, qv_max);
      s = Fh * sz / (f_acc + qv / kap + Fh);
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
      cr_fn_step_[c] += double(Pc) / dt;
    } else {
      q = 0;
    }
    if (last) {
      // The law's stored energy at the distance this crossing now enforces:
      // integral of F_half (span / x - 1) dx from s to span.
      const double se = std::min(sz, sp + q);
      cr_u_[c] = se > 0 ? Fh * (sz * std::log(sz / se) - (sz - se)) : 0.0;
    }
  }

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
    if (cr_stick_w_[c] < 0) cr_stick_w_[c] = s.cw, cr_stick_f_[c] = s.cf;
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

  // Stick or slip on each yarn, and the friction impulse of one pass (Eq 12-15).
  void pass_friction(int c, Real alpha, bool last, const FrictionSetup& s, CrossingImpulse& r) {
    const Crossing& cr = model_.crossings[c];
    const Real dt = Real(model_.dt);
    const double fwinv = s.fwinv;
    const double fn = cr_fn_step_[c];
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
      one_yarn(cr.warp_yarn, s.cw, cr_stick_w_[c], ft_w, s.lw);
      one_yarn(cr.weft_yarn, s.cf, cr_stick_f_[c], ft_f, s.lf);
    }
    if (ft_w != 0 || ft_f != 0) {
      // Force on the warp along its tangent, reaction on the weft; and vice versa (Eq 15).
      const V3 Fwarp = Real(ft_w) * s.Tw - Real(ft_f) * s.Tf;
      r.F = -alpha * dt * Fwarp;  // impulse on the weft point; the warp gets the reaction
      r.has_f = true;
      cr_ft_[c] = double(Fwarp.norm());
    }
    if (last) {
      cr_sliding_[c] = slid;
      cr_slip_[c] = moved / double(dt);
      cr_fn_[c] = fn;
      cr_stick_e_[c] = stored;
    }
  }

  // ------------------------------------------------------- projectile contact (Eq 18-22)
  void projectile_contact() {
    const int n = model_.node_count;
    const Real dt = Real(model_.dt);
    const Real R = Real(model_.shape.bounding_radius());
    const double mu_p = model_.projectile_friction;
    const double Mp = model_.projectile_mass;
    V3 impulse_normal = V3::Zero(), impulse_fric = V3::Zero();
    int touching = 0;
    // The nodes inside the projectile's bounding box, in node order (found by the threads,
    // each in its own range, then taken range by range).
    near_part_.resize(threads_);
#pragma omp parallel num_threads(threads_) if (threads_ > 1)
    {
      int lo, hi, t;
      my_share(n, lo, hi, t);
      std::vector<int>& mine = near_part_[t];
      mine.clear();
      for (int i = lo; i < hi; ++i) {
        const V3 rel = x_[i] - xp_;
        if (!(std::abs(rel.x()) > R || std::abs(rel.y()) > R || std::abs(rel.z()) > R)) mine.push_back(i);
      }
    }
    near_.clear();
    for (const auto& part : near_part_) near_.insert(near_.end(), part.begin(), part.end());
    for (const int i : near_) {
      const V3 rel = x_[i] - xp_;
      if (model_.fixed[i] == fix_all) continue;
      V3 nrm;
      const double sd = model_.shape.sdf(rel, nrm);
      if (sd > 0) continue;
      ++touching;
      ptouch_list_.push_back(i);
      if (model_.projectile_holds) {
        held_n_[i] = nrm;
        held_flag_[i] = 1;
        held_list_.push_back(i);
      }
      const double m = model_.mass[i];
      // Eq 19: push the node back onto the surface within one step (with the split, only
      // the part this step's approach made is a velocity change; see yarn contact).
      const Real pen = Real(-sd);
      Real push = pen / dt;
      if (model_.split_penetration) {
        push = std::min(push, std::max(Real(0), -(v_[i] - vp_).dot(nrm)));
        const Real shift = pen - push * dt;
        if (shift > Real(0)) {
          V3 dx = shift * nrm;
          zero_fixed(dx, model_.fixed[i]);
          x_[i] += dx;
          dx_contact_[i] += dx;
        }
      }
      V3 dv_n = push * nrm;
      // Eq 20-22: friction from the tangential relative velocity, capped by mu_p |f_n|.
      const V3 vr = v_[i] + dv_n - vp_;
      const V3 vt = vr - vr.dot(nrm) * nrm;
      const Real vtn = vt.norm();
      V3 dv_t = V3::Zero();
      if (vtn > Real(0)) {
        const Real cap = Real(mu_p) * push;  // mu_p |f_n| dt / m, f_n of Eq 19
        dv_t = -std::min(vtn, cap) * (vt / vtn);
      }
      zero_fixed(dv_t, model_.fixed[i]);
      zero_fixed(dv_n, model_.fixed[i]);
      v_[i] += dv_n + dv_t;
      x_[i] += dt * (dv_n + dv_t);
      dv_contact_[i] += dv_n;
      dv_pfriction_[i] += dv_t;
      impulse_normal -= Real(m) * dv_n;
      impulse_fric -= Real(m) * dv_t;
    }
    // The projectile takes the reactions: momentum is conserved.
    if (touching) {
      V3 dvp_n = impulse_normal / Real(Mp), dvp_t = impulse_fric / Real(Mp);
      // In a symmetric model the mirrored parts' reactions cancel the in-plane components.
      if (model_.mirror_x) dvp_n.x() = dvp_t.x() = 0;
      if (model_.mirror_y) dvp_n.y() = dvp_t.y() = 0;
      const V3 vp_old = vp_;
      vp_ += dvp_n + dvp_t;
      xp_ += dt * (vp_ - vp_old);
      // Work of the reactions on the projectile (it has no other force: v- = vp_old).
      const V3 vsum = vp_old + vp_;
      contact_cum_ -= 0.5 * Mp * double(dvp_n.dot(vsum));
      pfriction_cum_ -= 0.5 * Mp * double(dvp_t.dot(vsum));
      last_contact_time_ = time_ + model_.dt;
      had_contact_ = true;
    }
    proj_impulse_ = impulse_normal + impulse_fric;
    nodes_on_projectile_ = touching;
    projectile_force_ = double(proj_impulse_.norm() / dt);
  }

  double fabric_ke() const {
    double ke = 0;
    for (int i = 0; i < model_.node_count; ++i) ke += 0.5 * model_.mass[i] * double(v_[i].squaredNorm());
    return ke;
  }

  // A node the projectile pushed out this step rests on a rigid body: the yarn contact's
  // corrections do not move it back into the projectile (apply_impulse, shift_node, and the
  // effective mass in pass_normal); the impulse they would have pushed it in with acts on
  // the projectile instead. Summed here in node order (deterministic for any thread count).
  void release_held() {
    if (held_list_.empty()) return;
    V3 imp = V3::Zero(), imp_f = V3::Zero(), imp_c = V3::Zero();
    for (int i : held_list_) {
      imp += held_imp_[i];
      imp_f += held_fric_[i];
      imp_c += held_comp_[i];
      held_imp_[i].setZero();
      held_fric_[i].setZero();
      held_comp_[i].setZero();
      held_n_[i].setZero();
      held_flag_[i] = 0;
    }
    held_list_.clear();
    auto dv_of = [&](const V3& p) {
      V3 dv = p / Real(model_.projectile_mass);
      if (model_.mirror_x) dv.x() = 0;
      if (model_.mirror_y) dv.y() = 0;
      return dv;
    };
    const V3 dvp = dv_of(imp);
    const V3 vp_old = vp_;
    vp_ += dvp;
    xp_ += Real(model_.dt) * dvp;
    // The work on the projectile of the friction's and the compression's shares is theirs, the
    // rest the normal correction's.
    const V3 vsum = vp_old + vp_;
    const double hm = 0.5 * model_.projectile_mass;
    const double w_all = hm * double(dvp.dot(vsum));
    const double w_f = hm * double(dv_of(imp_f).dot(vsum)), w_c = hm * double(dv_of(imp_c).dot(vsum));
    contact_cum_ -= w_all - w_f - w_c;
    friction_work_cum_ += w_f;
    compress_work_cum_ += w_c;
    projectile_force_ = double((proj_impulse_ + imp).norm()) / model_.dt;
  }

  // The interpenetration left at the end of a step (after every correction), sampled every
  // kPenetrationCheckEvery steps: what the contact algorithm failed to resolve.
  static constexpr int kPenetrationCheckEvery = 8;
  void residual_penetration() {
    const int nc = int(model_.crossings.size());
    const int nb = (nc + kBatch - 1) / kBatch;
    double worst = 0;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(max : worst) if (threads_ > 1)
    for (int b = 0; b < nb; ++b) {
      const int c0 = b * kBatch, c1 = std::min(nc, c0 + kBatch);
      Window w[kBatch];
      ContactGeom g[kBatch];
      bool on[kBatch];
      for (int c = c0; c < c1; ++c) {
        on[c - c0] = cr_active_[c];
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
        const double D = cr.contact_distance, cmin = compressible_ ? cr.flattened_distance : D;
        const double dist = double(g[k].dist);
        const double pen = g[k].d.dot(n) >= Real(0) ? cmin - dist : (dist > D ? 0.0 : cmin + dist);
        worst = std::max(worst, pen);
      }
    }
    diag_.max_penetration = std::max(diag_.max_penetration, worst);
  }

  // The energy this step's position shifts put into the yarns (elements and bending springs),
  // from the laws themselves: the energy of each element or spring a shifted node belongs to,
  // at the end of the step, less its energy with the shifts taken back (its internal strain
  // e_v as it is: a shift is instantaneous). The velocity-driven part of the step's change is
  // the leapfrog's work of the element forces, so this split is exact in the shift. (The
  // trapezoid rule booked before, half with the next step's force, erred by shift x motion:
  // 20 % of the impact energy created over 1.4-3.6 ms of low-friction runs near the limit,
  // where whipping yarn ends were shifted tens of um per step at 200 m/s.)
  double shift_energy() {
    shifted_.clear();
    for (int i = 0; i < model_.node_count; ++i)
      if (dx_contact_[i].x() != Real(0) || dx_contact_[i].y() != Real(0) || dx_contact_[i].z() != Real(0))
        shifted_.push_back(i);
    if (shifted_.empty()) return 0;
    if (elem_mark_.empty()) elem_mark_.assign(model_.element_count, 0), bend_mark_.assign(model_.bend_k.size(), 0);
    if (++mark_ == 0) {  // wrapped: clear the marks
      std::fill(elem_mark_.begin(), elem_mark_.end(), 0u);
      std::fill(bend_mark_.begin(), bend_mark_.end(), 0u);
      mark_ = 1;
    }
    auto before = [&](int i) { return V3(x_[i] - dx_contact_[i]); };
    double du = 0;
    for (const int i : shifted_) {
      for (int k = inc_e_off_[i]; k < inc_e_off_[i + 1]; ++k) {
        const int e = inc_e_[k].first;
        if (elem_mark_[e] == mark_ || broken_flag_[e]) continue;
        elem_mark_[e] = mark_;
        const int a = model_.elem_a[e], b = model_.elem_b[e];
        du += element_energy_at(e, (x_[b] - x_[a]).norm()) - element_energy_at(e, (before(b) - before(a)).norm());
      }
      for (int k = inc_b_off_[i]; k < inc_b_off_[i + 1]; ++k) {
        const int sp = inc_b_[k].first;
        if (bend_mark_[sp] == mark_) continue;
        bend_mark_[sp] = mark_;
        du += bend_energy_at(sp, [&](int n) { return x_[n]; }) - bend_energy_at(sp, before);
      }
    }
    return du;
  }
  // An element's stored energy at length len with its current internal strain.
  double element_energy_at(int e, Real len) const {
    const double rest = model_.elem_rest[e], vol = model_.elem_area[e] * rest;
    Real eps = len / Real(rest) - Real(1), mat = eps, dg = Real(1);
    if (model_.crimp_strain > 0) crimp_stage(eps, mat, dg);
    if (model_.material == Material::zener) {
      const double sig = std::max(0.0, zener_.c.k1 * (double(mat) - double(ev_[e])));
      return zener_stored(zener_.c, sig, double(ev_[e])) * vol;
    }
    const double sig = std::max(0.0, model_.modulus_inst * double(mat));
    return sig * sig / (2 * model_.modulus_inst) * vol;
  }
  // A bending spring's energy with node positions from pos (internal_forces' law; 0 when
  // either element is broken).
  template <class Pos>
  double bend_energy_at(int sp, Pos&& pos) const {
    const int e1 = model_.bend_e1[sp], e2 = model_.bend_e2[sp];
    if (broken_flag_[e1] || broken_flag_[e2]) return 0;
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

  // Kinetic energy of v(t + dt/2) and the work of this step's corrections, in one sweep.
  // Work of a correction in the leapfrog's own energy statement: with v- = v(t - dt/2) and
  // v+ = v(t + dt/2) after all corrections, KE(v+) - KE(v-) = sum over forces F of
  // F . (dx(t - dt/2) + dx(t + dt/2)) / 2 exactly; a correction dv is a force m dv/dt, so
  // its work is m dv . (v- + v+) / 2. (Booking the bare kinetic-energy change of each
  // correction instead would count, every step, energy a resting contact never takes.)
  void finish_step() {
    double ke = 0, w_contact = 0, w_friction = 0, w_pfriction = 0, w_compress = 0;
    const int n = model_.node_count;
#pragma omp parallel for num_threads(threads_) schedule(static) reduction(+ : ke, w_contact, w_friction, w_pfriction, w_compress) if (threads_ > 1)
    for (int i = 0; i < n; ++i) {
      const double hm = 0.5 * model_.mass[i];
      ke += hm * double(v_[i].squaredNorm());
      const V3 vsum = v_prev_[i] + v_[i];
      w_contact += hm * double(dv_contact_[i].dot(vsum));
      w_friction += hm * double(dv_friction_[i].dot(vsum));
      dv_contact_[i].setZero();  // ready for the next step's corrections
      dv_friction_[i].setZero();
      if (compressible_) {
        w_compress += hm * double(dv_compress_[i].dot(vsum));
        dv_compress_[i].setZero();
      }
    }
    // The projectile's friction touched only the nodes on it (in node order).
    for (int i : ptouch_list_) {
      w_pfriction += 0.5 * model_.mass[i] * double(dv_pfriction_[i].dot(v_prev_[i] + v_[i]));
      dv_pfriction_[i].setZero();
    }
    ptouch_list_.clear();
    // External loads: F . (dx(t - dt/2) + dx(t + dt/2)) / 2.
    for (const auto& [i, F] : f_ext_) external_cum_ += 0.5 * double(model_.dt) * double(F.dot(v_prev_[i] + v_[i]));
    contact_cum_ -= w_contact;
    shift_cum_ -= shift_energy();
    compress_work_cum_ += w_compress;
    friction_work_cum_ += w_friction;
    pfriction_cum_ -= w_pfriction;
    ke_fabric_half_ = ke;
    ke_half_ = ke_fabric_half_ + 0.5 * model_.projectile_mass * double(vp_.squaredNorm());
    time_ += model_.dt;
    ++steps_;
  }

  void fail(const char* cause, const std::string& why) {
    if (!divergence_.empty()) return;
    divergence_ = "diverged at step " + std::to_string(steps_) + " (t = " + fmt(time_ * 1e6) + " us): " + why;
    divergence_cause_ = cause;
    divergence_step_ = steps_;
    divergence_time_ = time_;
  }
  static std::string fmt(double v) {
    char b[64];
    std::snprintf(b, sizeof b, "%.4g", v);
    return b;
  }

 private:
  int threads_ = 1;
  // Lanes in use (contact_lanes.h, element_lanes.h): asked for, double precision, and the
  // processor has them.
  static bool lanes_possible() {
    return std::is_same_v<Real, double> && lanes::available();
  }
  bool simd_ = lanes_possible();
  ZenerStepper zener_;
  std::vector<V3> x_, v_, f_, v_prev_;
  std::vector<V3> dv_contact_, dv_friction_, dv_pfriction_, dx_contact_;  // this step's corrections, per mechanism
  std::vector<V3> dv_compress_, sum_c_;  // the compression law's impulses (only when crossings are compressible)
  bool compressible_ = false;
  std::vector<double> cr_u_;        // per crossing: the compression law's stored energy at the end of the step
  std::vector<double> cr_stick_e_;  // per crossing: the stick penalty springs' energy (pass_friction)
  double stick_end_ = 0, stick_prev_ = 0, friction_work_cum_ = 0;
  double compress_end_ = 0, compress_prev_ = 0, compress_work_cum_ = 0;
  // Nodes the projectile pushed out this step: the surface normal (zero: not held), the
  // impulse the yarn contact passed through them to the projectile, and their list.
  std::vector<V3> held_n_, held_imp_;
  std::vector<V3> held_fric_, held_comp_;  // the friction's and the compression's shares of held_imp_
  std::vector<int> held_list_;
  std::vector<int> near_;                    // projectile_contact: nodes in its bounding box
  std::vector<std::vector<int>> near_part_;  // the same, per thread
  std::vector<int> ptouch_list_;             // nodes the projectile touched this step (their dv_pfriction_)
  std::vector<std::uint8_t> held_flag_;      // held_n_ is nonzero (a compact test for the hot loops)
  std::vector<V3> sum_n_, sum_f_, sum_s_;    // a pass's corrections summed per node (gather, finish_pass)
  V3 proj_impulse_ = V3::Zero();             // the projectile contact's impulse on the projectile this step
  std::vector<Real> strain_, prev_strain_, ev_, stress_;
  std::vector<std::uint8_t> broken_flag_;
  std::vector<V3> elem_force_, bend_force_;
  std::vector<double> elem_energy_;
  std::vector<int> inc_e_off_, inc_b_off_;
  std::vector<std::pair<int, Real>> inc_e_, inc_b_;
  std::vector<int> cr_kw_, cr_kf_;
  std::vector<int> rec_first_, rec_last_;  // (threads) node bounds of the pass's records, running
  std::vector<WindowIds> cr_win_;          // per crossing (load_window)
  std::vector<double> cr_stick_w_, cr_stick_f_, cr_fn_, cr_ft_, cr_slip_, cr_gap_, cr_fn_step_;
  // Each crossing's tracked node pair at the end of the last step and the offset between
  // its two nodes then (weft minus warp): how far the yarns moved against each other.
  struct LastPair {
    int kw, kf;
    V3 offset;
  };
  std::vector<LastPair> cr_last_;
  V3 pair_offset(int c, int kw, int kf) const {
    const Crossing& cr = model_.crossings[c];
    const int nw = model_.yarn_size(cr.warp_yarn), nf = model_.yarn_size(cr.weft_yarn);
    const int iw = model_.yarn_node(cr.warp_yarn, std::clamp(kw, 0, nw - 1));
    const int jf = model_.yarn_node(cr.weft_yarn, std::clamp(kf, 0, nf - 1));
    return x_[jf] - x_[iw];
  }
  std::vector<std::uint8_t> cr_active_, cr_sliding_, cr_event_;
  std::vector<CrossingImpulse> impulses_;
  std::vector<CrossingImpulse> held_records_;  // one thread: records touching held nodes (yarn_contact)
  enum : std::uint8_t { ev_skip = 1, ev_ravel = 2, ev_pass = 4, ev_lost = 8, ev_separated = 16 };
  V3 xp_, vp_;
  double ke_half_ = 0, ke_fabric_half_ = 0;
  double stored_now_ = 0, stored_prev_ = 0, viscous_cum_ = 0, viscous_prev_ = 0, released_cum_ = 0, released_prev_ = 0;
  double pfriction_cum_ = 0, contact_cum_ = 0, external_cum_ = 0;
  double shift_cum_ = 0;      // the position shifts' work against the yarn forces (ledger shift_work_J)
  std::vector<int> shifted_;  // shift_energy: the nodes shifted this step
  std::vector<unsigned> elem_mark_, bend_mark_;  // ... and the elements / springs already counted
  unsigned mark_ = 0;
  std::vector<std::pair<int, V3>> f_ext_;
  double escape_radius2_ = 1;
  // beta E_inst of the element damping (model's element_damping_beta times the instantaneous modulus).
  double damping_k_ = model_.element_damping_beta * model_.modulus_inst;
  double crimp_damping_k_ = model_.crimp_damping_beta * model_.modulus_inst;  // the same for yarn.crimp_damping
  std::vector<Real> crimp_damp_stress_;  // per element: the crimp damping's stress of the last step
  double damping_cum_ = 0;
};

}  // namespace

std::unique_ptr<Solver> make_solver(const Model& model, Precision precision, int threads) {
  if (precision == Precision::single_precision) return std::make_unique<SolverT<float>>(model, threads);
  return std::make_unique<SolverT<double>>(model, threads);
}

}  // namespace ravel

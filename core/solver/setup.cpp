// SolverT construction: the state from the model, the node incidence lists; make_solver.
#include "solver/solver_t.h"

namespace ravel::detail {

template <class Real>
SolverT<Real>::SolverT(const Model& m, int threads)
    : Solver(m), zener_(ZenerConstants{m.k1 > 0 ? m.k1 : 1, m.k2 > 0 ? m.k2 : 1, m.damping > 0 ? m.damping : 1}, m.dt) {
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

// ---------------------------------------------------------------- set-up
// Node -> (element, sign) and node -> (bending spring, weight) lists, so forces are
// gathered per node: race-free in parallel and independent of the thread count.
template <class Real>
inline void SolverT<Real>::build_incidence() {
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

// The two precisions (solver.h: Precision).
template SolverT<float>::SolverT(const Model& m, int threads);
template SolverT<double>::SolverT(const Model& m, int threads);

}  // namespace ravel::detail

namespace ravel {

std::unique_ptr<Solver> make_solver(const Model& model, Precision precision, int threads) {
  if (precision == Precision::single_precision) return std::make_unique<detail::SolverT<float>>(model, threads);
  return std::make_unique<detail::SolverT<double>>(model, threads);
}

}  // namespace ravel

// Set-up: the initial State of a model, the Context (node incidence lists, material
// constants), the SolverT that owns both, and make_solver.
#include "solver/solver_t.h"

namespace ravel::detail {

template <class Real>
State<Real> initial_state(const Model& model, const Context<Real>& ctx, RunState& run) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  State<Real> s;
  const int n = model.node_count, ne = model.element_count;
  s.x.resize(n);
  s.v.resize(n);
  s.f.resize(n);
  s.v_prev.assign(n, V3::Zero());
  s.corr.assign(n, {V3::Zero(), V3::Zero(), V3::Zero(), V3::Zero()});
  s.dv_pfriction.assign(n, V3::Zero());
  s.grip_payout.assign(model.grips.size(), 0.0);
  s.grip_heat.assign(model.grips.size(), 0.0);
  s.held_n.assign(n, V3::Zero());
  s.held_flag.assign(n, 0);
  s.pass_sum.assign(n, {V3::Zero(), V3::Zero(), V3::Zero(), V3::Zero()});
  s.held_imp.assign(n, V3::Zero());
  s.held_fric.assign(n, V3::Zero());
  s.held_comp.assign(n, V3::Zero());
  for (int i = 0; i < n; ++i) {
    s.x[i] = model.x0[i].template cast<Real>();
    s.v[i].setZero();
    s.f[i].setZero();
  }
  s.strain.assign(ne, Real(0));
  s.prev_strain.assign(ne, Real(0));
  s.ev.assign(ne, Real(0));
  s.stress.assign(ne, Real(0));
  s.crimp_damp_stress.assign(ctx.crimp_damping_k > 0 ? ne : 0, Real(0));
  s.broken_flag.assign(ne, 0);
  s.elem_force.assign(ne, V3::Zero());
  s.elem_energy.assign(ne, 0.0);
  s.bend_force.assign(model.bend_k.size(), V3::Zero());
  s.bend_energy.assign(model.bend_k.size(), 0.0);
  for (int e = 0; e < ne; ++e) {
    // Initial strain (slack for the straight-chord models).
    const Real len = (s.x[model.elem_b[e]] - s.x[model.elem_a[e]]).norm();
    Real eps = len / Real(model.elem_rest[e]) - Real(1), mat = eps,
         dg = Real(1);  // (eps: the yarn's own strain after crimp_stage)
    if (model.crimp_strain > 0) crimp_stage(model, eps, mat, dg);
    s.strain[e] = eps;
    s.prev_strain[e] = mat;
  }
  const int nc = int(model.crossings.size());
  s.cr.assign(nc, CrossingState<Real>{});
  for (int c = 0; c < nc; ++c) {
    s.cr[c].kw = model.crossings[c].warp_node;
    s.cr[c].kf = model.crossings[c].weft_node;
    s.cr[c].last = {s.cr[c].kw, s.cr[c].kf, pair_offset(model, s, c, s.cr[c].kw, s.cr[c].kf)};
  }
  s.xp = model.projectile_x0.cast<Real>();
  s.vp = (model.impact_velocity * model.flight_dir).template cast<Real>();
  // Initial ledger: all energy is the projectile's.
  s.book.ke_half = 0.5 * model.projectile_mass * double(s.vp.squaredNorm());
  run.ledger.projectile_ke_J = s.book.ke_half;
  return s;
}

template <class Real>
SolverT<Real>::SolverT(const Model& m, int threads)
    : Solver(m), ctx_(model_), s_(initial_state<Real>(model_, ctx_, run_)) {
  set_threads(threads);
}

// ---------------------------------------------------------------- set-up
// What the model determines: the material constants, and the node -> (element, sign) and
// node -> (bending spring, weight) lists, so forces are gathered per node: race-free in
// parallel and independent of the thread count.
template <class Real>
Context<Real>::Context(const Model& model)
    : simd(lanes_possible<Real>()),
      zener(ZenerConstants{model.k1 > 0 ? model.k1 : 1, model.k2 > 0 ? model.k2 : 1,
                           model.damping > 0 ? model.damping : 1},
            model.dt),
      compressible(model.compression != CrossingCompression::rigid),
      escape_radius2(std::pow(10.0 * (model.half_width + model.half_length) + 1.0, 2)),
      damping_k(model.element_damping_beta * model.modulus_inst),
      crimp_damping_k(model.crimp_damping_beta * model.modulus_inst) {
  const int n = model.node_count;
  if (simd) elem_mid.assign(3 * size_t(model.element_count), 0.0);
  const int nbend = int(model.bend_k.size());
  const int kBatch = lanes::kWidth;  // (internal_forces: groups of this many springs)
  bend_along.assign(size_t((nbend + kBatch - 1) / kBatch), 0);
  for (int s0 = 0; simd && s0 + kBatch <= nbend; s0 += kBatch) {
    const int first = model.bend_e1[size_t(s0)];
    bool along = first + kBatch < model.element_count;
    for (int l = 0; l < kBatch && along; ++l) {
      const size_t sp = size_t(s0 + l);
      along = model.bend_e1[sp] == first + l && model.bend_e2[sp] == first + l + 1 && model.bend_mirror[sp] < 0 &&
              model.elem_yarn[size_t(first + l)] == model.elem_yarn[size_t(first + l + 1)];
    }
    bend_along[size_t(s0 / kBatch)] = along;
  }
  std::vector<std::vector<int>> ne(n);
  std::vector<std::vector<std::pair<int, Real>>> nb(n);
  for (int e = 0; e < model.element_count; ++e) {
    ne[model.elem_b[e]].push_back(e);  // element force acts on b, -force on a
    ne[model.elem_a[e]].push_back(~e);
  }
  for (size_t s = 0; s < model.bend_k.size(); ++s) {
    // Spring pushes midpoint 2 by +F and midpoint 1 by -F; half to each end node.
    const int e1 = model.bend_e1[s], e2 = model.bend_e2[s];
    if (model.bend_mirror[s] >= 0) {
      // Mirror spring: State::bend_force is the force on this element's midpoint.
      nb[model.elem_a[e1]].push_back({int(s), Real(0.5)});
      nb[model.elem_b[e1]].push_back({int(s), Real(0.5)});
      continue;
    }
    // Adjoining elements share a node, which gets -F/2 and +F/2 of the same spring: no
    // force, and no entry (adding and taking away the same half would only round).
    const int ends[4] = {model.elem_a[e1], model.elem_b[e1], model.elem_a[e2], model.elem_b[e2]};
    for (int k = 0; k < 4; ++k) {
      const bool shared =
          (k < 2 ? (ends[k] == ends[2] || ends[k] == ends[3]) : (ends[k] == ends[0] || ends[k] == ends[1]));
      if (!shared) nb[ends[k]].push_back({int(s), Real(k < 2 ? -0.5 : 0.5)});
    }
  }
  inc_e_off.assign(n + 1, 0);
  inc_b_off.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) {
    inc_e_off[i + 1] = inc_e_off[i] + int(ne[i].size());
    inc_b_off[i + 1] = inc_b_off[i] + int(nb[i].size());
    for (int c : ne[i]) inc_e.push_back(c);
    for (auto& p : nb[i]) inc_b.push_back(p);
  }
}

// The two precisions (solver.h: Precision).
template struct Context<float>;
template struct Context<double>;
template SolverT<float>::SolverT(const Model& m, int threads);
template SolverT<double>::SolverT(const Model& m, int threads);

}  // namespace ravel::detail

namespace ravel {

std::unique_ptr<Solver> make_solver(const Model& model, Precision precision, int threads) {
  if (precision == Precision::single_precision) return std::make_unique<detail::SolverT<float>>(model, threads);
  return std::make_unique<detail::SolverT<double>>(model, threads);
}

}  // namespace ravel

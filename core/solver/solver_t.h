// SolverT<Real>: the Solver of solver.h in single or double precision. It owns the run's
// State (state.h) and Context (stage.h) and runs the stages of stage.h, one file each in this
// folder, in the order step() lists:
//
//   internal_forces.cpp     element strain -> stress (Zener / elastic, crimp stage), failure,
//                           bending springs, nodal forces
//   ledger.cpp              the energy book: the ledger row at t - dt/2, the kinetic energy
//                           and the corrections' work at the end of the step
//   integrate.cpp           Eq 1-2, the free update (the nodes' part, free_update in stage.h,
//                           runs inside internal_forces' force gather)
//   projectile_contact.cpp  Eq 18-22
//   hold.cpp, hold.h        the projectile's hold on the nodes it pushed out (the whole rule)
//   yarn_contact.cpp        Eq 5-17: crossing tracking, closest points, normal correction with
//                           the compression law, stick/slip friction
//   faults.cpp              divergence: the checks and the message
//   setup.cpp               the initial state and the context from the model, make_solver
//   state.cpp               the state hash
//   simd/                   the lane kernels (AVX2 / AVX-512) the stages call
//
// Private to core/: the rest of ravel sees the Solver interface of solver.h only.
#pragma once

#include <memory>
#include <string>

#include "solver.h"
#include "solver/stage.h"

namespace ravel::detail {

template <class Real>
class SolverT final : public Solver {
 public:
  using V3 = Eigen::Matrix<Real, 3, 1>;

  SolverT(const Model& m, int threads);

  void set_threads(int n) override {
#ifdef _OPENMP
    ctx_.threads = n <= 0 ? omp_get_num_procs() : n;
#else
    ctx_.threads = 1;
    (void)n;
#endif
  }
  void set_simd(bool on) override {
    ctx_.simd = on && lanes_possible<Real>();
  }
  bool simd_active() const override {
    return ctx_.simd;
  }

  void step() override {
    if (!run_.divergence.empty()) return;
    const Model& m = model_;
    internal_forces(m, s_, run_, ctx_);                 // Eq 3, 23: element stress; bending; failure; Eq 1-2 per node
    close_ledger_row(m, s_, run_, max_balance_error_);  // ledger at t - dt/2
    integrate(m, s_, run_, ctx_);                       // Eq 1-2: external loads, projectile, position check
    projectile_contact(m, s_, run_, ctx_);              // Eq 18-22
    if (!m.crossings.empty()) yarn_contact(m, s_, run_, ctx_);  // Eq 5-17
    release_held(m, s_, run_);                                  // the yarn contact's push on held nodes -> projectile
    if (!m.crossings.empty() && run_.steps % kPenetrationCheckEvery == 0) residual_penetration(m, s_, run_, ctx_);
    finish_step(m, s_, run_, ctx_);
    if (run_.steps % kProjectileCheckEvery == 0) check_projectile(m, s_, run_);
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
    s_.book.ke_half = fabric_ke(model_, s_) + 0.5 * model_.projectile_mass * double(s_.vp.squaredNorm());
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
  double grip_payout(int g) const override {
    return s_.grip_payout[size_t(g)];
  }
  double stress(int e) const override {
    return double(s_.stress[e]);
  }
  bool broken(int e) const override {
    return s_.broken_flag[e] != 0;
  }
  bool crossing_active(int c) const override {
    return s_.cr[c].active != 0;
  }
  bool crossing_sliding(int c) const override {
    return s_.cr[c].sliding != 0;
  }
  double crossing_normal_force(int c) const override {
    return s_.cr[c].fn;
  }
  double crossing_friction_force(int c) const override {
    return s_.cr[c].ft;
  }
  double crossing_friction_heat(int c) const override {
    return s_.cr[c].heat;
  }
  double crossing_slip_rate(int c) const override {
    return s_.cr[c].slip;
  }
  double crossing_gap(int c) const override {
    return s_.cr[c].gap;
  }
  int crossing_warp_node(int c) const override {
    return s_.cr[c].kw;
  }
  int crossing_weft_node(int c) const override {
    return s_.cr[c].kf;
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
  Context<Real> ctx_;  // what the model and the options determine, and the per-step scratch
  State<Real> s_;      // the run's dynamic state (plain data: copied, hashed and written as one)
};

}  // namespace ravel::detail

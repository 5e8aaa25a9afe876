// Stage projectile_contact (Eq 18-22).
#include "solver/hold.h"
#include "solver/stage.h"

namespace ravel::detail {

// ------------------------------------------------------- projectile contact (Eq 18-22)
template <class Real>
void projectile_contact(const Model& model, State<Real>& s, RunState& run, Context<Real>& ctx) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  const int n = model.node_count;
  const Real dt = Real(model.dt);
  const Real R = Real(model.shape.bounding_radius());
  const double mu_p = model.projectile_friction;
  const double Mp = model.projectile_mass;
  V3 impulse_normal = V3::Zero(), impulse_fric = V3::Zero();
  int touching = 0;
  // The nodes inside the projectile's bounding box, in node order (found by the threads,
  // each in its own range, then taken range by range).
  ctx.near_part.resize(ctx.threads);
#pragma omp parallel num_threads(ctx.threads) if (ctx.threads > 1)
  {
    int lo, hi, t;
    my_share(n, lo, hi, t);
    std::vector<int>& mine = ctx.near_part[t];
    mine.clear();
    for (int i = lo; i < hi; ++i) {
      const V3 rel = s.x[i] - s.xp;
      if (!(std::abs(rel.x()) > R || std::abs(rel.y()) > R || std::abs(rel.z()) > R)) mine.push_back(i);
    }
  }
  ctx.near.clear();
  for (const auto& part : ctx.near_part) ctx.near.insert(ctx.near.end(), part.begin(), part.end());
  for (const int i : ctx.near) {
    const V3 rel = s.x[i] - s.xp;
    if (model.fixed[i] == fix_all) continue;
    V3 nrm;
    const double sd = model.shape.sdf(rel, nrm);
    if (sd > 0) continue;
    ++touching;
    s.ptouch_list.push_back(i);
    if (model.projectile_holds) hold_node(s, i, nrm);  // (hold.h)
    const double m = model.mass[i];
    // Eq 19: push the node back onto the surface within one step (with the split, only
    // the part this step's approach made is a velocity change; see yarn contact).
    const Real pen = Real(-sd);
    Real push = pen / dt;
    if (model.split_penetration) {
      push = std::min(push, std::max(Real(0), -(s.v[i] - s.vp).dot(nrm)));
      const Real shift = pen - push * dt;
      if (shift > Real(0)) {
        V3 dx = shift * nrm;
        zero_fixed(dx, model.fixed[i]);
        s.x[i] += dx;
        s.corr[i].dx_contact += dx;
      }
    }
    V3 dv_n = push * nrm;
    // Eq 20-22: friction from the tangential relative velocity, capped by mu_p |f_n|.
    const V3 vr = s.v[i] + dv_n - s.vp;
    const V3 vt = vr - vr.dot(nrm) * nrm;
    const Real vtn = vt.norm();
    V3 dv_t = V3::Zero();
    if (vtn > Real(0)) {
      const Real cap = Real(mu_p) * push;  // mu_p |f_n| dt / m, f_n of Eq 19
      dv_t = -std::min(vtn, cap) * (vt / vtn);
    }
    zero_fixed(dv_t, model.fixed[i]);
    zero_fixed(dv_n, model.fixed[i]);
    s.v[i] += dv_n + dv_t;
    s.x[i] += dt * (dv_n + dv_t);
    s.corr[i].dv_contact += dv_n;
    s.dv_pfriction[i] += dv_t;
    impulse_normal -= Real(m) * dv_n;
    impulse_fric -= Real(m) * dv_t;
  }
  // The projectile takes the reactions: momentum is conserved.
  if (touching) {
    V3 dvp_n = impulse_normal / Real(Mp), dvp_t = impulse_fric / Real(Mp);
    // In a symmetric model the mirrored parts' reactions cancel the in-plane components.
    if (model.mirror_x) dvp_n.x() = dvp_t.x() = 0;
    if (model.mirror_y) dvp_n.y() = dvp_t.y() = 0;
    const V3 vp_old = s.vp;
    s.vp += dvp_n + dvp_t;
    s.xp += dt * (s.vp - vp_old);
    // Work of the reactions on the projectile (it has no other force: v- = vp_old).
    const V3 vsum = vp_old + s.vp;
    s.book.contact_cum -= 0.5 * Mp * double(dvp_n.dot(vsum));
    s.book.pfriction_cum -= 0.5 * Mp * double(dvp_t.dot(vsum));
    run.last_contact_time = run.time + model.dt;
    run.had_contact = true;
  }
  s.proj_impulse = impulse_normal + impulse_fric;
  run.nodes_on_projectile = touching;
  run.projectile_force = double(s.proj_impulse.norm() / dt);
}

// The two precisions (solver.h: Precision).
template void projectile_contact(const Model&, State<float>&, RunState&, Context<float>&);
template void projectile_contact(const Model&, State<double>&, RunState&, Context<double>&);

}  // namespace ravel::detail

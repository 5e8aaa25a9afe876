// The projectile's hold (solver.projectile_holds, docs/MODEL.md §4), in one place.
//
// The rule: a node the projectile pushed out this step rests on a rigid body, so the yarn
// contact that follows does not move it back *into* the projectile. Five parts, each a
// function here, used by the stages named:
//
//   hold_node             projectile_contact: the node is held, with the surface normal n
//   held_mobility         yarn_contact (pass_normal): a held node yields to a crossing's
//                         correction along u only in the directions free of the projectile
//                         (1 - (u.n)^2 when the correction would push it in, else 1)
//   crossing_keeps_hold   yarn_contact (pass_normal): if the hold leaves a crossing less than
//                         kMinHeldMobility of its mobility (both yarns pinned so that they
//                         could separate only into the projectile), the crossing is
//                         corrected as if nothing were held
//   pass_to_projectile    yarn_contact (gather): the part of an impulse on a held node that
//   keep_out              pushes into the projectile is passed to it (its share of friction
//                         and compression noted for their own work); a position shift keeps
//                         only the part that does not
//   release_held          after the yarn contact (hold.cpp): the impulses passed on act on the
//                         projectile, and every hold ends with the step
#pragma once

#include <vector>

#include "solver/stage.h"

namespace ravel::detail {

// The least share of a crossing's mobility the hold may leave (see crossing_keeps_hold).
constexpr double kMinHeldMobility = 0.25;

template <class Real>
inline void hold_node(State<Real>& s, int i, const Eigen::Matrix<Real, 3, 1>& n) {
  s.held_n[i] = n;
  s.held_flag[i] = 1;
  s.held_list.push_back(i);
}

// The share of a held node's mobility left for a correction along u with signed weight w.
template <class Real>
inline Real held_mobility(const State<Real>& s, int i, Real w, const Eigen::Matrix<Real, 3, 1>& u) {
  const Real un = u.dot(s.held_n[i]);
  return w * un < Real(0) ? Real(1) - un * un : Real(1);
}

// Whether a crossing honours the hold, given its inverse effective mass with the held nodes'
// mobility (winv) and without (winv_free): not when the hold leaves it less than
// kMinHeldMobility of its mobility (both yarns pinned so that they could separate only into
// the projectile, which a rigid body cannot resolve); it is then corrected as if nothing
// were held.
template <class Real>
inline bool crossing_keeps_hold(Real winv, Real winv_free) {
  return winv >= Real(kMinHeldMobility) * winv_free;
}

// Take out of impulse P on held node i the part pushing into the projectile, and pass it on
// (to held_imp; also to part, per node, when the impulse is friction's or compression's).
template <class Real>
inline void pass_to_projectile(State<Real>& s, int i, Eigen::Matrix<Real, 3, 1>& P,
                               std::vector<Eigen::Matrix<Real, 3, 1>>* part) {
  const Real pn = P.dot(s.held_n[i]);
  if (pn < Real(0)) {
    s.held_imp[i] += pn * s.held_n[i];
    if (part) (*part)[i] += pn * s.held_n[i];
    P -= pn * s.held_n[i];
  }
}

// Take out of a position shift dx of held node i the part into the projectile.
template <class Real>
inline void keep_out(const State<Real>& s, int i, Eigen::Matrix<Real, 3, 1>& dx) {
  const Real dn = dx.dot(s.held_n[i]);
  if (dn < Real(0)) dx -= dn * s.held_n[i];
}

}  // namespace ravel::detail

// Weave builder: turns a Scene into the network of paper §2 (sliding: two nodes per
// crossing, L1 apart, zig-zag yarns) or of reference [8] (pin-jointed: one node per
// crossing), keeping only the part the scene's symmetry requires (SPEC §6).
#include "model.h"

#include <cmath>
#include <stdexcept>

#include "geometry.h"

namespace ravel {

namespace {

struct Grid {
  int i_min, i_max, j_min, j_max;  // modelled global crossing indices (inclusive)
  int hx, hy;                      // half counts: global I in [-hx, hx]
};

}  // namespace

SymmetryChoice choose_symmetry(const Scene& scene) {
  const auto& f = scene.fabric;
  const auto& p = scene.projectile;
  const bool single = f.weave == Weave::single_yarn;
  const ClampedEdges clamped = single ? ClampedEdges{false, false, true, true} : f.clamped;
  const bool normal_strike = p.obliquity_deg == 0.0;
  bool can_x = !single && p.offset_x_m == 0.0 && normal_strike && clamped.left == clamped.right;
  bool can_y = p.offset_y_m == 0.0 && clamped.bottom == clamped.top;
  std::string why_not;
  if (!can_x) {
    if (single)
      why_not += "a single yarn has no x extent to save; ";
    else if (p.offset_x_m != 0.0)
      why_not += "off-centre in x; ";
    else if (!normal_strike)
      why_not += "oblique strike breaks x symmetry; ";
    else
      why_not += "left/right clamps differ; ";
  }
  if (!can_y) why_not += p.offset_y_m != 0.0 ? "off-centre in y; " : "bottom/top clamps differ; ";
  if (scene.solver.symmetry == SymmetryMode::full) {
    can_x = can_y = false;
    why_not = "solver.symmetry = full forces the whole fabric";
  }
  return {can_x, can_y, why_not};
}

Model build_model(const Scene& scene) {
  Model m;
  const auto& f = scene.fabric;
  const auto& y = scene.yarn;
  const auto& p = scene.projectile;
  const int k = f.yarns_per_element;
  const double L0 = f.spacing_m * k;
  // A lumped mesh (k real yarns per modelled yarn) scales the crossing geometry with the
  // spacing, so its crimp angle L1 / L0, and with it the interlock a sliding yarn climbs,
  // stays the real fabric's (docs/MODEL.md §1).
  const double L1 = f.crossing_gap_m * k;
  const bool single = f.weave == Weave::single_yarn;
  const bool sliding = !single && scene.solver.model == ContactModel::sliding;
  m.contact = single ? ContactModel::pin_jointed : scene.solver.model;
  m.half_width = f.width_m / 2;
  m.half_length = f.length_m / 2;
  m.thickness = f.thickness_m;
  m.clamped = single ? ClampedEdges{false, false, true, true} : f.clamped;

  // ---- symmetry (SPEC §6): mirror planes the scene allows
  const SymmetryChoice sym = choose_symmetry(scene);
  const bool can_x = sym.mirror_x, can_y = sym.mirror_y;
  const std::string& why_not = sym.why_not;
  m.mirror_x = can_x;
  m.mirror_y = can_y;
  m.symmetry_factor = (can_x ? 2.0 : 1.0) * (can_y ? 2.0 : 1.0);
  m.symmetry_label = can_x && can_y ? "quarter" : (can_x || can_y) ? "half" : "full";
  if (can_x && can_y)
    m.symmetry_reason = "centred normal strike with symmetric clamps: a quarter reproduces the whole (SPEC 6)";
  else if (can_x || can_y)
    m.symmetry_reason = std::string("mirror plane ") + (can_x ? "x = 0" : "y = 0") + " only (" + why_not + ")";
  else
    m.symmetry_reason = why_not.empty() ? "no symmetry" : why_not;
  while (!m.symmetry_reason.empty() && (m.symmetry_reason.back() == ' ' || m.symmetry_reason.back() == ';'))
    m.symmetry_reason.pop_back();

  Grid g;
  g.hx = single ? 0 : int(std::floor(m.half_width / L0 + 1e-9));
  g.hy = int(std::floor(m.half_length / L0 + 1e-9));
  g.i_min = can_x ? 0 : -g.hx;
  g.i_max = g.hx;
  g.j_min = can_y ? 0 : -g.hy;
  g.j_max = g.hy;
  // Modelled yarns: their real yarn indices (positions I L0, J L0) and weights w (real
  // yarns each stands for: its spacing to its neighbours, in L0). Without grading every
  // index from i_min to i_max, w = 1 (k when uniformly lumped, already in L0).
  const int kf = single || k > 1 ? 1 : f.far_yarns_per_element;
  const bool graded = kf > 1;
  auto modelled = [&](int lo, int hi, double centre_m, bool clamp_lo, bool clamp_hi) {
    std::vector<int> idx;
    if (!graded) {
      for (int I = lo; I <= hi; ++I) idx.push_back(I);
      return idx;
    }
    // Every real yarn within the band; outside it every kf-th, counted from the edge
    // inwards (so the clamped or free edge yarn is modelled and mirrored halves match).
    const double band = f.full_resolution_m + 1e-9 * L0;
    const double clamp_band = f.clamp_resolution_m + 1e-9 * L0;
    auto fine = [&](int I) {
      return std::abs(I * L0 - centre_m) <= band || (clamp_lo && (I - lo) * L0 <= clamp_band) ||
             (clamp_hi && (hi - I) * L0 <= clamp_band);
    };
    std::vector<char> keep(size_t(hi - lo + 1), 0);
    for (int I = lo; I <= hi; ++I) keep[size_t(I - lo)] = fine(I);
    if (lo == 0) keep[0] = 1;  // the mirror plane's yarn
    // Each run [a, b] of coarse yarns: an edge run every kf-th from the edge; a run between
    // two modelled yarns a - 1 and b + 1 in equal gaps of at most kf.
    for (int a = lo; a <= hi;) {
      if (keep[size_t(a - lo)]) {
        ++a;
        continue;
      }
      int b = a;
      while (b + 1 <= hi && !keep[size_t(b + 1 - lo)]) ++b;
      if (b == hi)
        for (int I = hi; I >= a; I -= kf) keep[size_t(I - lo)] = 1;
      else if (a == lo)
        for (int I = lo; I <= b; I += kf) keep[size_t(I - lo)] = 1;
      else {
        const int span = b - a + 2, gaps = (span + kf - 1) / kf;
        for (int t = 1; t < gaps; ++t) keep[size_t(a - 1 + (t * span + gaps / 2) / gaps - lo)] = 1;
      }
      a = b + 1;
    }
    for (int I = lo; I <= hi; ++I)
      if (keep[size_t(I - lo)]) idx.push_back(I);
    return idx;
  };
  const std::vector<int> gi =
      single ? std::vector<int>{0}
             : modelled(g.i_min, g.i_max, p.offset_x_m, m.clamped.left && g.i_min < 0, m.clamped.right);
  const std::vector<int> gj = modelled(g.j_min, g.j_max, p.offset_y_m, m.clamped.bottom && g.j_min < 0, m.clamped.top);
  auto weights = [&](const std::vector<int>& idx, bool mirrored) {
    std::vector<double> w(idx.size(), 1.0);
    if (!graded) return w;
    for (size_t a = 0; a < idx.size(); ++a) {
      const double left = a > 0 ? idx[a] - idx[a - 1] : (mirrored && idx[a] == 0 ? 1.0 : -1.0);
      const double right = a + 1 < idx.size() ? idx[a + 1] - idx[a] : -1.0;
      // (an edge yarn: itself and half the gap inside it, so the weights add up to the real count)
      w[a] = left > 0 && right > 0 ? 0.5 * (left + right) : 0.5 * (1.0 + std::max(left, right));
    }
    return w;
  };
  const std::vector<double> wi_of = weights(gi, can_x), wj_of = weights(gj, can_y);
  // Zig-zag parity by modelled index (every yarn alternates over and under), anchored at
  // the centre yarn so the centre crossing keeps the warp on top; without grading the
  // modelled index is I - i_min, and this is the parity of I + J.
  auto anchor = [](const std::vector<int>& idx) {
    size_t best = 0;
    for (size_t a = 0; a < idx.size(); ++a)
      if (std::abs(idx[a]) < std::abs(idx[best])) best = a;
    return int(best) - idx[best];
  };
  const int pi0 = anchor(gi), pj0 = anchor(gj);
  // Warp yarn a (it runs along y) over weft yarn b at their crossing.
  auto warp_on_top = [&](int a, int b) { return ((a + pi0 + b + pj0) % 2 + 2) % 2 == 0; };
  const int ni = int(gi.size()), nj = int(gj.size());

  // ---- material
  m.material = y.material;
  m.k1 = y.k1_pa;
  m.k2 = y.k2_pa;
  m.damping = y.damping_pa_s;
  m.modulus_inst = y.material == Material::zener ? y.k1_pa : y.modulus_pa;
  m.density = y.density_kg_m3;
  m.failure_strain = y.failure_strain;
  m.breakable = y.breakable;
  m.friction = y.friction;
  m.friction_penalty = scene.solver.friction_penalty;
  m.split_penetration = scene.solver.split_penetration;
  m.projectile_holds = scene.solver.projectile_holds;
  m.contact_iterations = scene.solver.contact_iterations;
  m.compression = f.crossing_compression;

  const double node_mass = f.node_mass_kg * double(k) * double(k);
  const double area = y.area_m2 * k;
  auto plane_factor = [&](int I, int J) { return (can_x && I == 0 ? 0.5 : 1.0) * (can_y && J == 0 ? 0.5 : 1.0); };
  auto fixed_bits = [&](int I, int J) {
    std::uint8_t b = 0;
    if (can_x && I == 0) b |= fix_x;
    if (can_y && J == 0) b |= fix_y;
    const bool on_left = I == -g.hx, on_right = I == g.hx, on_bottom = J == -g.hy, on_top = J == g.hy;
    if ((on_left && m.clamped.left) || (on_right && m.clamped.right) || (on_bottom && m.clamped.bottom) ||
        (on_top && m.clamped.top))
      b = fix_all;
    return b;
  };
  auto add_node = [&](const Vec3d& x, double mass, std::uint8_t fix) {
    m.x0.push_back(x);
    m.mass.push_back(mass);
    m.inv_mass.push_back(fix == fix_all ? 0.0 : 1.0 / mass);
    m.fixed.push_back(fix);
    return int(m.x0.size()) - 1;
  };

  // ---- nodes and yarns
  m.yarn_offset.push_back(0);
  if (single) {
    // One straight warp yarn through the centre, clamped at both ends.
    m.warp_count = 1;
    for (int J = g.j_min; J <= g.j_max; ++J) {
      std::uint8_t fix = (J == -g.hy || J == g.hy) ? fix_all : (can_y && J == 0 ? fix_y : 0);
      int n = add_node(Vec3d(0, J * L0, 0), node_mass * (can_y && J == 0 ? 0.5 : 1.0), fix);
      m.yarn_nodes.push_back(n);
    }
    m.yarn_offset.push_back(int(m.yarn_nodes.size()));
    m.yarn_family.push_back(warp);
    m.yarn_grid.push_back(0);
  } else if (sliding) {
    m.warp_count = ni;
    m.weft_count = nj;
    // Node ids interleave the two yarns at each crossing: warp node (I, J), then weft node
    // (I, J), with J running fastest, the order the contact pass visits crossings in. A
    // crossing's six window nodes then lie in three sequential streams (grid rows I - 1, I,
    // I + 1) instead of one weft node per crossing a whole row apart (see docs/MODEL.md §1).
    // Graded: a node stands for w_I x w_J real crossings' yarn, and each yarn's crimp
    // amplitude follows its own spacing (the warp's the wefts' w_J), so the crimp angle is
    // the real fabric's on both yarns (docs/MODEL.md §1).
    std::vector<int> wid(size_t(ni) * nj), fid(size_t(ni) * nj);
    for (int a = 0; a < ni; ++a)
      for (int b = 0; b < nj; ++b) {
        const int I = gi[size_t(a)], J = gj[size_t(b)];
        const bool warp_top = warp_on_top(a, b);
        const size_t at = size_t(a) * nj + b;
        const double wa = wi_of[size_t(a)], wb = wj_of[size_t(b)];
        const double mass = node_mass * wa * wb * plane_factor(I, J);
        const double zw = 0.5 * L1 * wb, zf = 0.5 * L1 * wa;
        wid[at] = add_node(Vec3d(I * L0, J * L0, warp_top ? zw : -zw), mass, fixed_bits(I, J));
        fid[at] = add_node(Vec3d(I * L0, J * L0, warp_top ? -zf : zf), mass, fixed_bits(I, J));
      }
    for (int a = 0; a < ni; ++a) {
      for (int b = 0; b < nj; ++b) m.yarn_nodes.push_back(wid[size_t(a) * nj + b]);
      m.yarn_offset.push_back(int(m.yarn_nodes.size()));
      m.yarn_family.push_back(warp);
      m.yarn_grid.push_back(gi[size_t(a)]);
    }
    for (int b = 0; b < nj; ++b) {
      for (int a = 0; a < ni; ++a) m.yarn_nodes.push_back(fid[size_t(a) * nj + b]);
      m.yarn_offset.push_back(int(m.yarn_nodes.size()));
      m.yarn_family.push_back(weft);
      m.yarn_grid.push_back(gj[size_t(b)]);
    }
  } else {
    // Pin-jointed: one node per crossing carrying both yarns' mass.
    m.warp_count = ni;
    m.weft_count = nj;
    std::vector<int> id(size_t(ni) * nj);
    for (int a = 0; a < ni; ++a)
      for (int b = 0; b < nj; ++b) {
        const int I = gi[size_t(a)], J = gj[size_t(b)];
        id[size_t(a) * nj + b] =
            add_node(Vec3d(I * L0, J * L0, 0), 2 * node_mass * wi_of[size_t(a)] * wj_of[size_t(b)] * plane_factor(I, J),
                     fixed_bits(I, J));
      }
    for (int a = 0; a < ni; ++a) {
      for (int b = 0; b < nj; ++b) m.yarn_nodes.push_back(id[size_t(a) * nj + b]);
      m.yarn_offset.push_back(int(m.yarn_nodes.size()));
      m.yarn_family.push_back(warp);
      m.yarn_grid.push_back(gi[size_t(a)]);
    }
    for (int b = 0; b < nj; ++b) {
      for (int a = 0; a < ni; ++a) m.yarn_nodes.push_back(id[size_t(a) * nj + b]);
      m.yarn_offset.push_back(int(m.yarn_nodes.size()));
      m.yarn_family.push_back(weft);
      m.yarn_grid.push_back(gj[size_t(b)]);
    }
  }
  m.node_count = int(m.x0.size());

  // ---- elements and bending springs
  // Rest length: the crimped length sqrt(L0^2 + L1^2) of the zig-zag (paper Fig. 1; with L0
  // and L1 scaled alike when lumped). The pin-jointed model puts its nodes at z = 0, L0
  // apart: its elements take up the crimp in a soft crimp stage of the yarn law before the
  // yarn stretches (crimp interchange, ref [8]; see Model::crimp_strain). A single yarn is
  // straight.
  const double crimped = single ? L0 : std::sqrt(L0 * L0 + L1 * L1);
  const double rest_len = sliding || single ? crimped : L0;
  if (!sliding && !single) {
    m.crimp_strain = crimped / L0 - 1;
    m.crimp_fraction = y.crimp_modulus_fraction;
    m.crimp_width = m.crimp_strain;
  }
  m.yarn_end_free.resize(m.yarn_count());
  m.yarn_start_mirror.assign(m.yarn_count(), -1);
  for (int yy = 0; yy < m.yarn_count(); ++yy) {
    m.yarn_elem_offset.push_back(int(m.elem_a.size()));
    const bool is_warp = m.yarn_family[yy] == warp;
    const int grid = m.yarn_grid[yy];
    const bool on_plane = is_warp ? (can_x && grid == 0) : (can_y && grid == 0);
    const double yarn_w = !graded ? 1.0 : is_warp ? wi_of[size_t(yy)] : wj_of[size_t(yy - m.warp_count)];
    const double a = area * yarn_w * (on_plane ? 0.5 : 1.0);
    const int n = m.yarn_size(yy);
    // Graded: each element's rest length is its own (the zig-zag's, or the node spacing of
    // the pin-jointed net); the crimped length sets its bending stiffness.
    auto graded_rest = [&](int kk) {
      const Vec3d d = m.x0[m.yarn_node(yy, kk + 1)] - m.x0[m.yarn_node(yy, kk)];
      return sliding ? d.norm() : std::hypot(d.x(), d.y());
    };
    auto bend_len = [&](int e) { return graded ? m.elem_rest[size_t(e)] * (1 + m.crimp_strain) : crimped; };
    for (int kk = 0; kk + 1 < n; ++kk) {
      m.elem_a.push_back(m.yarn_node(yy, kk));
      m.elem_b.push_back(m.yarn_node(yy, kk + 1));
      m.elem_yarn.push_back(yy);
      m.elem_rest.push_back(graded ? graded_rest(kk) : rest_len);
      m.elem_area.push_back(a);
    }
    const int e0 = m.yarn_elem_offset.back();
    for (int kk = 0; kk + 2 < n; ++kk) {
      m.bend_e1.push_back(e0 + kk);
      m.bend_e2.push_back(e0 + kk + 1);
      m.bend_k.push_back(y.bending_fraction * m.modulus_inst * a / bend_len(e0 + kk));
      // Midpoint distance at rest: along the yarn the zig-zag midpoints sit L0 apart.
      const Vec3d m1 = 0.5 * (m.x0[m.yarn_node(yy, kk)] + m.x0[m.yarn_node(yy, kk + 1)]);
      const Vec3d m2 = 0.5 * (m.x0[m.yarn_node(yy, kk + 1)] + m.x0[m.yarn_node(yy, kk + 2)]);
      m.bend_rest.push_back((m2 - m1).norm());
      m.bend_mirror.push_back(-1);
    }
    // A yarn that crosses a symmetry plane at its first node has, in the full fabric, a
    // bending spring between its first element and that element's mirror image.
    const int ax = (!is_warp && can_x) ? 0 : (is_warp && can_y) ? 1 : -1;
    m.yarn_start_mirror[yy] = std::int8_t(ax);
    if (ax >= 0 && n >= 2) {
      const Vec3d mid = 0.5 * (m.x0[m.yarn_node(yy, 0)] + m.x0[m.yarn_node(yy, 1)]);
      m.bend_e1.push_back(e0);
      m.bend_e2.push_back(e0);
      m.bend_k.push_back(y.bending_fraction * m.modulus_inst * a / bend_len(e0));
      m.bend_rest.push_back(2 * std::abs(mid[ax]));
      m.bend_mirror.push_back(ax);
    }
    // Free ends: the first node is free unless clamped or on a symmetry plane.
    const int first = m.yarn_node(yy, 0), last = m.yarn_node(yy, n - 1);
    std::uint8_t ef = 0;
    if (m.fixed[first] != fix_all && !(m.fixed[first] & (is_warp ? fix_y : fix_x))) ef |= 1;
    if (m.fixed[last] != fix_all) ef |= 2;
    m.yarn_end_free[yy] = ef;
  }
  m.yarn_elem_offset.push_back(int(m.elem_a.size()));
  m.element_count = int(m.elem_a.size());

  // ---- slipping clamps (docs/MODEL.md §7): each yarn end held by a clamp across the yarn
  // is fed from the clamp against the grip, scaled like the yarn's cross-section (k real yarns when
  // lumped, its graded weight, half on a symmetry plane). A node in two clamps (a corner of
  // a ply clamped on adjacent edges) stays rigid.
  if (f.clamp == ClampKind::slipping && m.clamped.any()) {
    const double tol = 1e-6 * L0, ex = g.hx * L0, ey = g.hy * L0;
    auto held = [&](int i, int ax) {
      const double c = m.x0[size_t(i)][ax], e = ax == 0 ? ex : ey;
      const bool lo = ax == 0 ? m.clamped.left : m.clamped.bottom, hi = ax == 0 ? m.clamped.right : m.clamped.top;
      return (lo && c <= -e + tol) || (hi && c >= e - tol);
    };
    m.grip_of_elem.assign(size_t(m.element_count), -1);
    m.clamp_depth = f.clamp_depth_m;
    for (int yy = 0; yy < m.yarn_count(); ++yy) {
      const int ax = m.yarn_family[yy] == warp ? 1 : 0, n = m.yarn_size(yy), e0 = m.yarn_elem_offset[yy];
      if (n < 2) continue;
      const double grip = f.clamp_grip_n * m.elem_area[size_t(e0)] / y.area_m2;
      for (const auto& [i, e] : {std::pair{m.yarn_node(yy, 0), e0}, std::pair{m.yarn_node(yy, n - 1), e0 + n - 2}}) {
        if (m.fixed[size_t(i)] != fix_all || !held(i, ax) || held(i, 1 - ax)) continue;
        m.grip_of_elem[size_t(e)] = int(m.grips.size());
        m.grips.push_back({e, i, grip});
      }
    }
  }

  // ---- crossings (sliding)
  const double D = 0.5 * f.thickness_m * k;
  if (sliding) {
    for (int wi = 0; wi < m.warp_count; ++wi) {
      for (int fj = 0; fj < m.weft_count; ++fj) {
        Crossing c;
        c.warp_yarn = wi;
        c.weft_yarn = m.warp_count + fj;
        c.grid_i = gi[size_t(wi)];
        c.grid_j = gj[size_t(fj)];
        const double wa = wi_of[size_t(wi)], wb = wj_of[size_t(fj)], wab = 0.5 * (wa + wb);
        c.warp_node = fj;  // warp yarn wi has a node at every J
        c.weft_node = wi;
        // Inside a clamp both yarns are held: no contact to resolve there. (Keeping such
        // crossings lets a correction at a clamped node act through a tiny lever on its
        // free neighbour, which is numerically unstable.)
        if (m.fixed[m.yarn_node(c.warp_yarn, c.warp_node)] == fix_all ||
            m.fixed[m.yarn_node(c.weft_yarn, c.weft_node)] == fix_all)
          continue;
        const bool warp_top = warp_on_top(wi, fj);
        // t_warp x t_weft ~ y x x = -z; n must point from warp to weft: -z when the warp is on top.
        c.side = warp_top ? 1.0 : -1.0;
        // Rest distance between the two yarns' adjoining segments: the zig-zag brings them a
        // little closer than L1 next to the node, so D is capped by it (no spring-back at t=0).
        double best = 1e300;
        for (int sa = c.warp_node - 1; sa <= c.warp_node; ++sa) {
          if (sa < 0 || sa + 1 >= m.yarn_size(c.warp_yarn)) continue;
          for (int sb = c.weft_node - 1; sb <= c.weft_node; ++sb) {
            if (sb < 0 || sb + 1 >= m.yarn_size(c.weft_yarn)) continue;
            double s, t;
            Vec3d pa, pb;
            closest_points_segments(m.x0[m.yarn_node(c.warp_yarn, sa)], m.x0[m.yarn_node(c.warp_yarn, sa + 1)],
                                    m.x0[m.yarn_node(c.weft_yarn, sb)], m.x0[m.yarn_node(c.weft_yarn, sb + 1)], s, t,
                                    pa, pb);
            best = std::min(best, (pb - pa).norm());
          }
        }
        // Graded: the two yarns' thicknesses scale with the real yarns each stands for (their
        // mean sets D and c_min), and the crossing stands for w_I x w_J real ones.
        c.contact_distance = std::min(D * wab, best);
        if (m.compression == CrossingCompression::hyperbolic) {
          c.flattened_distance = std::min(f.flattened_gap_m * k * wab, c.contact_distance);
          c.compression_force =
              f.compression_force_n * double(k) * double(k) * wa * wb * plane_factor(c.grid_i, c.grid_j);
          c.packed_distance = std::clamp(f.packed_gap_m * k * wab, c.flattened_distance, c.contact_distance);
          c.flattening_force =
              f.flattening_force_n * double(k) * double(k) * wa * wb * plane_factor(c.grid_i, c.grid_j);
        } else {
          c.flattened_distance = c.contact_distance;
          c.packed_distance = c.contact_distance;
        }
        m.crossings.push_back(c);
      }
    }
  }

  // ---- time step (Eq 4)
  m.wave_speed = std::sqrt(m.modulus_inst / m.density);
  m.shortest_element = 1e300;
  // (the yarn's own length: a pin-jointed element's material is its crimped length)
  for (double r : m.elem_rest) m.shortest_element = std::min(m.shortest_element, r * (1 + m.crimp_strain));
  m.dt = scene.solver.dt_factor * m.shortest_element / m.wave_speed;
  // Central differences on a chain of lumped masses m joined by springs k are stable for
  // dt < 2/omega_max = sqrt(m_node/k) (each node feels two springs plus 5 % bending);
  // expressed as alpha = dt c / L this is sqrt(m_node / (rho A L)) / sqrt(1 + bending).
  {
    const double m_line = f.node_mass_kg * k * k * (sliding || single ? 1.0 : 2.0);
    const double k_axial = m.modulus_inst * area / crimped;
    const double bend = y.bending_fraction;
    // Pin-jointed nodes carry two yarns' mass, but each direction only one yarn's stiffness.
    m.critical_dt_factor = std::sqrt(m_line / k_axial) / std::sqrt(1.0 + bend) * m.wave_speed / m.shortest_element;
    m.held_dt_factor = m.critical_dt_factor * (!single && m.projectile_holds ? std::sqrt(3.0) / 2 : 1.0);
  }
  m.end_time = scene.solver.end_time_s;
  // Snap damping: a fraction zeta of critical at the chain's highest axial frequency
  // omega_max = 2 c / L, as a stress beta E_inst d(eps)/dt with beta = 2 zeta / omega_max.
  m.element_damping_beta = scene.solver.snap_damping * m.shortest_element / m.wave_speed;
  // The pin-jointed stretch damping (yarn.crimp_damping), on the same basis, on the apparent strain.
  m.crimp_damping_beta = m.crimp_strain > 0 ? y.crimp_damping * m.shortest_element / m.wave_speed : 0.0;

  // ---- projectile
  m.shape.kind = p.shape;
  m.shape.radius = 0.5 * p.diameter_m;
  m.shape.length = p.length_m;
  const double th = p.obliquity_deg * M_PI / 180.0;
  m.flight_dir = Vec3d(std::sin(th), 0, -std::cos(th));
  m.shape.axis = m.flight_dir;
  m.projectile_mass_full = p.mass_kg;
  m.projectile_mass = p.mass_kg / m.symmetry_factor;
  m.impact_velocity = p.velocity_mps;
  m.projectile_friction = p.friction;
  // (A graded mesh's coarse yarns crimp higher: only the fabric under the projectile counts.)
  double z_top = -1e300;
  const double reach = m.shape.bounding_radius() + 2 * f.spacing_m;
  for (const auto& x : m.x0)
    if (!graded || std::hypot(x.x() - p.offset_x_m, x.y() - p.offset_y_m) <= reach) z_top = std::max(z_top, x.z());
  // Place the projectile just touching the fabric top: find the centre offset along
  // -flight_dir at which the sdf of the strike point equals zero.
  const Vec3d strike(p.offset_x_m, p.offset_y_m, z_top);
  double lo = 0, hi = 4 * m.shape.bounding_radius() + 1e-3;
  for (int it = 0; it < 200; ++it) {
    double mid = 0.5 * (lo + hi);
    Vec3d c = strike - mid * m.flight_dir;
    Vec3d nrm;
    if (m.shape.sdf(Vec3d(strike - c), nrm) < 0)
      lo = mid;
    else
      hi = mid;
  }
  m.projectile_x0 = strike - hi * m.flight_dir;
  return m;
}

}  // namespace ravel

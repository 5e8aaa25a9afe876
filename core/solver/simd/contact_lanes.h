// The closest points of the yarn contact (Eq 5-8 with the tie band, docs/MODEL.md §4) for
// four crossings at once, in the AVX2 lanes of processors that have them, and the rest of
// the geometry that depends on the crossing windows' positions alone.
//
// The lane code performs, lane by lane, exactly the IEEE operations of the one-crossing code
// in solver/yarn_contact.cpp (YarnContact::closest, the side test of pass_normal, chord_coord, seg_len), in
// the same order, and this file is compiled without
// floating-point contraction: the results are the same bit for bit (tested), only computed
// four at a time. It covers the regular case, all four segments next to the tracked pair
// intact; the solver computes the other crossings one at a time.
#pragma once

namespace ravel::lanes {

constexpr int kWidth = 4;
// A node that projects this close to an end of the chord through its neighbours (a yarn
// folded back at it) keeps the chord's linear material coordinate (YarnContact::chord_coord).
constexpr double kChordNodeMin = 0.01;

// Four crossing windows. The inputs point into each crossing's own window (read in place:
// copying them into lane order first would stall every vector load on the copies), the
// outputs are in lane order (structure of arrays, [..][lane]).
struct ClosestBatch {
  // In, per lane: positions of warp nodes kw-1..kw+1 and weft nodes kf-1..kf+1 (9
  // consecutive doubles each: x y z of each node), and the tie band (kTieBand * D).
  const double* xw[kWidth];
  const double* xf[kWidth];
  double band[kWidth];
  double side[kWidth];  // the crossing's side sign (YarnContact::pass_normal)
  // Out, as YarnContact::ContactGeom: mean contact vector warp -> weft, smallest |d|, weights
  // on the three warp / weft nodes, and the first closest pair's segments (0: kw-1 / kf-1,
  // 1: kw / kf) and fractions.
  double d[3][kWidth], dist[kWidth], ww[3][kWidth], wf[3][kWidth], a[kWidth], b[kWidth];
  long long iw[kWidth], jf[kWidth];
  // Out, the rest of the geometry the correction uses, as the one-crossing code computes it
  // from the window: the side-test normal n (YarnContact::pass_normal), |d| and d / |d|; the
  // chord offsets of the contact along the warp and the weft (clamped to [-1, 1]: the
  // material coordinate is the tracked node + offset) and the chords' unit tangents
  // (YarnContact::chord_coord); the lengths of warp segments kw-1, kw and weft segments kf-1, kf.
  double n[3][kWidth], dlen[kWidth], ud[3][kWidth];
  double offw[kWidth], offf[kWidth], tw[3][kWidth], tf[3][kWidth];
  double lw[2][kWidth], lf[2][kWidth];
  // Out: whether a pair of the window's nodes other than the middle one is strictly closer
  // than the middle pair (YarnContact::track would move the tracked pair; all else above then
  // belongs to a pair that is not the nearest and is recomputed by the solver).
  long long moved[kWidth];
};

// The end of the yarn contact's last pass over the nodes [lo, hi) (YarnContact::
// finish_last_pass): each node's pass sums become its corrections, velocity and position,
// and the ledger's node sums and shifted nodes are taken (Book::finish_step). One node at a
// time, its x y z in three lanes of a vector (the fourth unused): the same IEEE operations,
// component by component and in the same order, as the one-node code, dot products and
// squared norms summed (x + y) + z as Eigen sums a three-vector; so the same bits.
struct NodeFinish {
  // In/out, per node (pointers to node 0 of the solver's arrays): the pass sums n f s c
  // (12 doubles a node: State::PassSum, cleared here), the step's corrections dv_contact
  // dv_friction dv_compress dx_contact (12 doubles: State::Corrections; the three velocity
  // changes are cleared here, booked), velocities and positions (3 doubles a node).
  double *pass_sum, *corr, *v, *x;
  // In: velocities before the step (3 a node), inverse masses, masses, fixed axes (FixedAxis).
  const double *v_prev, *inv_mass, *mass;
  const unsigned char* fixed;
  double dt;
  bool compressible;  // the crossings have a compression law (its sums are used)
  int lo, hi;
  // Out: the sums over [lo, hi) in node order (kinetic energy of v(t + dt/2), work of the
  // contact's, friction's and compression's velocity changes), and the nodes whose dx_contact
  // is not zero, in order, into `shifted` (room for hi - lo), their number in shifted_count.
  double ke, w_contact, w_friction, w_compress;
  int* shifted;
  int shifted_count;
};

// The instruction set the lane kernels run with on this processor, chosen once: AVX-512
// (F, VL, DQ) if it has it, else AVX2, else none. The environment variable RAVEL_LANES=avx2
// caps the choice at AVX2. Both give the same numbers bit for bit.
enum class Isa { none, avx2, avx512 };
Isa isa();
const char* isa_name(Isa i);
// Whether this processor runs the lane code at all.
bool available();

// Fills the outputs of all four lanes. Only call when available().
void closest4(ClosestBatch& s);
// Only call when available().
void finish_nodes(NodeFinish& s);

// The kernels of each instruction set, for tests that compare them (call only what the
// processor has).
namespace avx2 {
void closest4(ClosestBatch& s);
void finish_nodes(NodeFinish& s);
}  // namespace avx2
namespace avx512 {
void closest4(ClosestBatch& s);
void finish_nodes(NodeFinish& s);
}  // namespace avx512

}  // namespace ravel::lanes

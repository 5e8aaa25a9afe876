// Which lane kernels this processor runs (see contact_lanes.h, lanes_kernels.inc): the
// AVX-512 build where the processor has AVX-512 F, VL and DQ, else the AVX2 build, else none.
#include "contact_lanes.h"

#include <cstdlib>
#include <cstring>

#include "element_lanes.h"

namespace ravel::lanes {

namespace {

Isa detect() {
  __builtin_cpu_init();
  const char* want = std::getenv("RAVEL_LANES");  // "avx2" caps the choice (tests, comparisons)
  const bool cap_avx2 = want && std::strcmp(want, "avx2") == 0;
  if (!cap_avx2 && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
      __builtin_cpu_supports("avx512dq"))
    return Isa::avx512;
  if (__builtin_cpu_supports("avx2")) return Isa::avx2;
  return Isa::none;
}

}  // namespace

Isa isa() {
  static const Isa chosen = detect();
  return chosen;
}

bool available() {
  return isa() != Isa::none;
}

const char* isa_name(Isa i) {
  return i == Isa::avx512 ? "avx512" : i == Isa::avx2 ? "avx2" : "none";
}

void closest4(ClosestBatch& s) {
  if (isa() == Isa::avx512)
    avx512::closest4(s);
  else
    avx2::closest4(s);
}

void finish_nodes(NodeFinish& s) {
  if (isa() == Isa::avx512)
    avx512::finish_nodes(s);
  else
    avx2::finish_nodes(s);
}

bool zener4(ElementBatch& s) {
  return isa() == Isa::avx512 ? avx512::zener4(s) : avx2::zener4(s);
}

double gather_forces(const NodeForces& s, double max_r2) {
  return isa() == Isa::avx512 ? avx512::gather_forces(s, max_r2) : avx2::gather_forces(s, max_r2);
}

void bend4(BendBatch& s) {
  if (isa() == Isa::avx512)
    avx512::bend4(s);
  else
    avx2::bend4(s);
}

}  // namespace ravel::lanes

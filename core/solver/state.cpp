// The state hash (Solver::state_hash): FNV-1a over the raw bytes of the dynamic state.
#include "solver/solver_t.h"

namespace ravel {

std::uint64_t Solver::state_hash() const {
  std::uint64_t h = kFnvBasis;
  hash_into(h);
  return h;
}

namespace detail {

template <class Real>
void SolverT<Real>::hash_into(std::uint64_t& h) const {
  s_.hash(h);
}

// The two precisions (solver.h: Precision).
template void SolverT<float>::hash_into(std::uint64_t& h) const;
template void SolverT<double>::hash_into(std::uint64_t& h) const;

}  // namespace detail
}  // namespace ravel

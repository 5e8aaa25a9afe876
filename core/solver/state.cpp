// The state hash (Solver::state_hash): FNV-1a over the raw bytes of the dynamic state.
#include "solver/solver_t.h"

namespace ravel {

std::uint64_t Solver::state_hash() const {
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a offset basis
  hash_into(h);
  return h;
}

namespace detail {

namespace {
void fnv(std::uint64_t& h, const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
}
}  // namespace

template <class Real>
void SolverT<Real>::hash_into(std::uint64_t& h) const {
  fnv(h, x_.data(), x_.size() * sizeof(V3));
  fnv(h, v_.data(), v_.size() * sizeof(V3));
  fnv(h, ev_.data(), ev_.size() * sizeof(Real));
  fnv(h, broken_flag_.data(), broken_flag_.size());
  fnv(h, cr_stick_w_.data(), cr_stick_w_.size() * sizeof(double));
  fnv(h, cr_stick_f_.data(), cr_stick_f_.size() * sizeof(double));
  fnv(h, xp_.data(), sizeof(V3));
  fnv(h, vp_.data(), sizeof(V3));
}

// The two precisions (solver.h: Precision).
template void SolverT<float>::hash_into(std::uint64_t& h) const;
template void SolverT<double>::hash_into(std::uint64_t& h) const;

}  // namespace detail
}  // namespace ravel

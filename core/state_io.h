// StateWriter / StateReader: a run's dynamic state as bytes, for checkpoints.
//
// A checkpoint holds what a run needs to continue exactly where it was: every array and
// scalar the solver carries from one step to the next (positions, velocities, the
// elements' internal strains, the crossings' tracked pairs and stick points, the ledger's
// running sums, ...) and the Simulation's own (the history, the outcome detection's timers).
// What a run derives from its scene (the model, incidence lists, the time step) is not
// written: a checkpoint is read into a Simulation built from the same scene, which the
// header's fingerprint checks. Arrays are written as their raw bytes (trivially copyable
// elements), in native byte order: a checkpoint is for the machine and build that wrote it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace ravel {

// FNV-1a over raw bytes: the state hash, the checkpoint's checksum, short names from text.
constexpr std::uint64_t kFnvBasis = 1469598103934665603ull;
inline void fnv1a(std::uint64_t& h, const void* data, std::size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
}

class StateWriter {
 public:
  template <class T>
  void pod(const T& v) {
    static_assert(std::is_standard_layout<T>::value, "raw bytes only for plain data");
    bytes(&v, sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    static_assert(std::is_standard_layout<T>::value, "raw bytes only for plain data");
    const std::uint64_t n = v.size();
    pod(n);
    bytes(v.data(), n * sizeof(T));
  }
  void str(const std::string& s) {
    const std::uint64_t n = s.size();
    pod(n);
    bytes(s.data(), n);
  }
  void strings(const std::vector<std::string>& v) {
    const std::uint64_t n = v.size();
    pod(n);
    for (const auto& s : v) str(s);
  }
  // Section marks: a reader checks it is where the writer was.
  void mark(std::uint32_t tag) { pod(tag); }
  const std::string& data() const { return out_; }

 private:
  void bytes(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string out_;
};

class StateReader {
 public:
  explicit StateReader(const std::string& in) : in_(in) {}
  template <class T>
  void pod(T& v) {
    static_assert(std::is_standard_layout<T>::value, "raw bytes only for plain data");
    bytes(&v, sizeof(T));
  }
  template <class T>
  void vec(std::vector<T>& v) {
    std::uint64_t n = 0;
    pod(n);
    // An array the model sizes (it is not empty in a freshly built solver) must come back
    // with that size: a checkpoint of the same scene cannot have another.
    if (!v.empty() && n != v.size())
      fail("an array of " + std::to_string(n) + " items where the model has " + std::to_string(v.size()));
    if (n > (in_.size() - pos_) / std::max<std::size_t>(1, sizeof(T))) fail("an array runs past the end");
    v.resize(n);
    bytes(v.data(), n * sizeof(T));
  }
  void str(std::string& s) {
    std::uint64_t n = 0;
    pod(n);
    if (n > in_.size() - pos_) fail("a string runs past the end");
    s.assign(in_.data() + pos_, n);
    pos_ += n;
  }
  void strings(std::vector<std::string>& v) {
    std::uint64_t n = 0;
    pod(n);
    if (n > in_.size() - pos_) fail("a list runs past the end");
    v.resize(n);
    for (auto& s : v) str(s);
  }
  void mark(std::uint32_t tag) {
    std::uint32_t t = 0;
    pod(t);
    if (t != tag) fail("section mark " + std::to_string(tag) + " not found (a different build wrote it?)");
  }
  bool at_end() const { return pos_ == in_.size(); }
  std::size_t position() const { return pos_; }
  void seek(std::size_t pos) {
    if (pos > in_.size()) fail("seek past the end");
    pos_ = pos;
  }

 private:
  void bytes(void* p, std::size_t n) {
    if (n > in_.size() - pos_) fail("truncated");
    if (n) std::memcpy(p, in_.data() + pos_, n);
    pos_ += n;
  }
  [[noreturn]] void fail(const std::string& why) const { throw std::runtime_error("checkpoint: " + why); }
  const std::string& in_;
  std::size_t pos_ = 0;
};

}  // namespace ravel

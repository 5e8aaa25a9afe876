#include "timeline.h"

#include <algorithm>

namespace ravel::app {

namespace {
template <class T>
std::size_t vbytes(const std::vector<T>& v) {
  return v.size() * sizeof(T);
}
}  // namespace

std::size_t Timeline::Kept::bytes() const {
  return sizeof(Kept) + vbytes(node_pos) + vbytes(node_vel) + vbytes(node_slip_rate) + vbytes(node_friction_j_per_g) +
         vbytes(elem_strain) + vbytes(elem_stress_pa) + vbytes(elem_broken) + vbytes(crossing_warp_node) +
         vbytes(crossing_weft_node) + vbytes(crossing_normal_force_n) + vbytes(crossing_slip_rate) +
         vbytes(crossing_active);
}

Timeline::Kept Timeline::keep(const Frame& f, long step) {
  Kept k;
  k.time_s = f.time_s;
  k.step = step;
  k.perforated = f.perforated;
  k.projectile_pos = f.projectile_pos;
  k.node_pos = f.node_pos;
  k.node_vel = f.node_vel;
  k.node_slip_rate = f.node_slip_rate;
  k.node_friction_j_per_g = f.node_friction_j_per_g;
  k.elem_strain = f.elem_strain;
  k.elem_stress_pa = f.elem_stress_pa;
  k.elem_broken = f.elem_broken;
  k.crossing_warp_node = f.crossing_warp_node;
  k.crossing_weft_node = f.crossing_weft_node;
  k.crossing_normal_force_n = f.crossing_normal_force_n;
  k.crossing_slip_rate = f.crossing_slip_rate;
  k.crossing_active = f.crossing_active;
  return k;
}

void Timeline::reset(long run_id) {
  run_id_ = run_id;
  spacing_ = 0;
  seen_ = 0;
  bytes_ = 0;
  kept_.clear();
  kept_.shrink_to_fit();
  skeleton_ = Frame{};
}

void Timeline::add(const Frame& f, long step) {
  if (f.node_pos.empty()) return;
  if (!kept_.empty() && f.time_s <= kept_.back().time_s) return;  // nothing new
  ++seen_;
  if (kept_.empty()) {
    skeleton_ = f;  // the parts that do not change; the per-frame arrays are dropped below
    for (auto* v : {&skeleton_.node_pos, &skeleton_.node_vel}) v->clear(), v->shrink_to_fit();
    for (auto* v : {&skeleton_.node_slip_rate, &skeleton_.node_friction_j_per_g, &skeleton_.elem_strain,
                    &skeleton_.elem_stress_pa, &skeleton_.crossing_normal_force_n, &skeleton_.crossing_slip_rate})
      v->clear(), v->shrink_to_fit();
    skeleton_.elem_broken.clear();
    skeleton_.crossing_active.clear();
    skeleton_.crossing_warp_node.clear();
    skeleton_.crossing_weft_node.clear();
  }
  Kept k = keep(f, step);
  const std::size_t n = kept_.size();
  // The newest kept frame is provisional while it is closer than the spacing to the one
  // before it: a later frame replaces it.
  if (n >= 2 && kept_[n - 1].time_s - kept_[n - 2].time_s < spacing_) {
    bytes_ -= kept_.back().bytes();
    kept_.back() = std::move(k);
  } else {
    kept_.push_back(std::move(k));
  }
  bytes_ += kept_.back().bytes();
  if (bytes_ > budget_) thin();
}

void Timeline::thin() {
  while (bytes_ > budget_ && kept_.size() > 2) {
    const double span = kept_.back().time_s - kept_.front().time_s;
    spacing_ = spacing_ > 0 ? 2 * spacing_ : 2 * span / double(kept_.size() - 1);
    std::vector<Kept> keep_list;
    keep_list.reserve(kept_.size() / 2 + 2);
    bytes_ = 0;
    for (std::size_t i = 0; i < kept_.size(); ++i) {
      const bool last = i + 1 == kept_.size();
      if (i == 0 || last || kept_[i].time_s - keep_list.back().time_s >= spacing_) {
        bytes_ += kept_[i].bytes();
        keep_list.push_back(std::move(kept_[i]));
      }
    }
    kept_ = std::move(keep_list);
  }
}

void Timeline::set_budget_bytes(std::size_t b) {
  budget_ = b;
  if (bytes_ > budget_) thin();
}

std::size_t Timeline::index_at(double t_s) const {
  if (kept_.empty()) return 0;
  auto it = std::upper_bound(kept_.begin(), kept_.end(), t_s, [](double t, const Kept& k) { return t < k.time_s; });
  if (it == kept_.begin()) return 0;
  return std::size_t(it - kept_.begin()) - 1;
}

Frame Timeline::frame(std::size_t i) const {
  Frame f = skeleton_;
  const Kept& k = kept_[i];
  f.time_s = k.time_s;
  f.perforated = k.perforated;
  f.projectile_pos = k.projectile_pos;
  f.node_pos = k.node_pos;
  f.node_vel = k.node_vel;
  f.node_slip_rate = k.node_slip_rate;
  f.node_friction_j_per_g = k.node_friction_j_per_g;
  f.elem_strain = k.elem_strain;
  f.elem_stress_pa = k.elem_stress_pa;
  f.elem_broken = k.elem_broken;
  f.crossing_warp_node = k.crossing_warp_node;
  f.crossing_weft_node = k.crossing_weft_node;
  f.crossing_normal_force_n = k.crossing_normal_force_n;
  f.crossing_slip_rate = k.crossing_slip_rate;
  f.crossing_active = k.crossing_active;
  return f;
}

}  // namespace ravel::app

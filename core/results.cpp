#include "results.h"

#include "state_io.h"

#include <cstdint>

#include <cctype>

#include <unistd.h>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

namespace ravel {

namespace fs = std::filesystem;

void prepare_output_dir(const std::string& dir) {
  if (dir.empty()) throw OutputError("--out: no output folder given");
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw OutputError("--out " + dir + ": exists and is not a folder");
  fs::create_directories(dir, ec);
  if (ec) throw OutputError("--out " + dir + ": cannot create the folder (" + ec.message() + ")");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw OutputError("--out " + dir + ": the folder is not writable (" + std::strerror(errno) + ")");
}

void write_file_atomic(const std::string& path, const std::string& content) {
  const fs::path p(path);
  std::random_device rd;
  const fs::path tmp = p.parent_path() / ("." + p.filename().string() + ".tmp" + std::to_string(::getpid()) + "_" +
                                          std::to_string(rd() % 1000000));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw OutputError(path + ": cannot write (" + std::strerror(errno) + ")");
    out.write(content.data(), std::streamsize(content.size()));
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw OutputError(path + ": write failed (disk full?)");
    }
  }
  std::error_code ec;
  fs::rename(tmp, p, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw OutputError(path + ": cannot move the finished file into place (" + ec.message() + ")");
  }
}

bool write_file_atomic(const std::string& path, const std::string& content, std::string* error) {
  try {
    write_file_atomic(path, content);
    return true;
  } catch (const OutputError& e) {
    if (error) *error = e.what();
    return false;
  }
}

std::vector<std::string> history_columns() {
  return {"t_s",
          "projectile_z_m",
          "projectile_velocity_mps",
          "projectile_ke_J",
          "fabric_ke_J",
          "strain_energy_J",
          "viscous_J",
          "damping_J",
          "friction_work_J",
          "stick_energy_J",
          "projectile_friction_J",
          "contact_loss_J",
          "shift_work_J",
          "released_J",
          "compression_J",
          "compression_loss_J",
          "external_work_J",
          "total_energy_J",
          "balance_error",
          "broken_warp",
          "broken_weft",
          "max_strain",
          "projectile_contact_force_N",
          "yarn_contact_force_N",
          "nodes_on_projectile",
          "sliding_crossings",
          "stuck_crossings",
          "clamp_friction_J"};
}

std::string history_csv(const std::vector<HistoryRow>& rows) {
  std::string out;
  const auto cols = history_columns();
  for (size_t i = 0; i < cols.size(); ++i) out += (i ? "," : "") + cols[i];
  out += "\n";
  char buf[64];
  auto num = [&](double v) {
    std::snprintf(buf, sizeof buf, "%.9g", v);
    out += buf;
  };
  for (const auto& r : rows) {
    const Ledger& l = r.ledger;
    const double vals[] = {r.t_s,
                           r.projectile_z_m,
                           r.projectile_velocity_mps,
                           l.projectile_ke_J,
                           l.fabric_ke_J,
                           l.strain_energy_J,
                           l.viscous_J,
                           l.damping_J,
                           l.friction_work_J,
                           l.stick_energy_J,
                           l.projectile_friction_J,
                           l.contact_loss_J,
                           l.shift_work_J,
                           l.released_J,
                           l.compression_J,
                           l.compression_loss_J,
                           l.external_work_J,
                           l.total(),
                           r.balance_error,
                           double(r.broken_warp),
                           double(r.broken_weft),
                           r.max_strain,
                           r.projectile_contact_force_N,
                           r.yarn_contact_force_N,
                           double(r.nodes_on_projectile),
                           double(r.sliding_crossings),
                           double(r.stuck_crossings),
                           l.clamp_friction_J};
    for (size_t i = 0; i < std::size(vals); ++i) {
      if (i) out += ",";
      num(vals[i]);
    }
    out += "\n";
  }
  return out;
}

std::string safe_file_name(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const bool keep = std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '-' || ch == '_';
    out += keep ? ch : '_';
  }
  while (!out.empty() && out.front() == '.') out.front() = '_';
  if (out.size() > 80) out.resize(80);
  return out.empty() ? "scene" : out;
}

std::string short_hash(const std::string& text) {
  std::uint64_t h = kFnvBasis;
  fnv1a(h, text.data(), text.size());
  char b[17];
  std::snprintf(b, sizeof b, "%08x", unsigned((h >> 32) ^ h));
  return b;
}

std::string line_ranges(const std::vector<int>& lines) {
  std::string out;
  for (size_t i = 0; i < lines.size();) {
    size_t j = i;
    while (j + 1 < lines.size() && lines[j + 1] <= lines[j] + 1) ++j;  // a run of consecutive lines
    if (!out.empty()) out += ", ";
    out += std::to_string(lines[i]);
    if (lines[j] != lines[i]) out += ".." + std::to_string(lines[j]);
    i = j + 1;
  }
  return out;
}

std::string summary_json(const Summary& s, const Scene& scene) {
  nlohmann::ordered_json j;
  j["scene"] = s.scene_name;
  j["status"] = to_string(s.status);
  j["end_reason"] = to_string(s.end_reason);
  j["diagnosis"] = s.diagnosis;
  // A diverged run: what stopped it, in which step, at which simulated time (else null).
  const bool fault = s.status == RunStatus::diverged && !s.divergence_cause.empty();
  j["divergence_cause"] = fault ? nlohmann::ordered_json(s.divergence_cause) : nlohmann::ordered_json(nullptr);
  j["divergence_step"] = fault ? nlohmann::ordered_json(s.divergence_step) : nlohmann::ordered_json(nullptr);
  j["divergence_time_s"] = fault ? nlohmann::ordered_json(s.divergence_time_s) : nlohmann::ordered_json(nullptr);
  // A diverged run has no outcome: whether it perforated, its residual velocity and the
  // energy it absorbed are undefined (null), not the numbers of a broken state.
  const bool undefined = s.status == RunStatus::diverged;
  auto outcome = [&](auto v) { return undefined ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(v); };
  j["perforated"] = outcome(s.perforated);
  j["impact_velocity_mps"] = s.impact_velocity_mps;
  j["residual_velocity_mps"] = outcome(s.residual_velocity_mps);
  j["energy_absorbed_J"] = outcome(s.energy_absorbed_J);
  j["perforation_time_s"] = s.perforation_time_s >= 0 && !undefined ? nlohmann::ordered_json(s.perforation_time_s)
                                                                    : nlohmann::ordered_json(nullptr);
  j["decided_passing"] = s.decided_passing;
  j["energy_balance_error"] = s.energy_balance_error;
  j["friction_work_J"] = outcome(s.friction_work_J);
  if (scene.fabric.clamp == ClampKind::slipping) {
    j["clamp"] = "slipping";
    j["clamp_grip_n"] = scene.fabric.clamp_grip_n;
    j["clamp_friction_J"] = s.clamp_friction_J;
    j["clamp_depth_mm"] = scene.fabric.clamp_depth_m * 1e3;
    j["clamp_slip_max_mm"] = s.clamp_slip_max_m * 1e3;
    j["clamp_pulled_out_yarns"] = int(std::lround(s.clamp_pulled_out));
  }
  j["friction_work_to_first_break_J"] = outcome(s.friction_work_to_first_break_J);
  j["friction_work_to_perforation_J"] = outcome(s.friction_work_to_perforation_J);
  j["first_break_distance_mm"] = s.first_break_distance_m >= 0 && !undefined
                                     ? nlohmann::ordered_json(s.first_break_distance_m * 1e3)
                                     : nlohmann::ordered_json(nullptr);
  j["broken_before_perforation_elements"] = s.broken_before_perforation;
  j["broken_near_clamp_elements"] = s.broken_near_clamp;
  j["first_break_time_s"] = s.first_break_time_s >= 0 && !undefined ? nlohmann::ordered_json(s.first_break_time_s)
                                                                    : nlohmann::ordered_json(nullptr);
  j["yarn_friction"] = scene.yarn.friction;
  j["failure_strain"] = scene.yarn.failure_strain;
  j["model"] = s.model;
  j["model_reason"] = s.model_reason;
  j["contact_model"] = s.contact_model;
  j["precision"] = scene.solver.precision == Precision::double_precision ? "double" : "float";
  j["yarns_per_element"] = scene.fabric.yarns_per_element;
  if (scene.fabric.far_yarns_per_element > 1) {
    j["far_yarns_per_element"] = scene.fabric.far_yarns_per_element;
    j["full_resolution_mm"] = scene.fabric.full_resolution_m * 1e3;
    j["clamp_resolution_mm"] = scene.fabric.clamp_resolution_m * 1e3;
  }
  j["node_count"] = s.node_count;
  j["element_count"] = s.element_count;
  j["crossing_count"] = s.crossing_count;
  j["modelled_node_count"] = s.modelled_node_count;
  j["modelled_element_count"] = s.modelled_element_count;
  j["modelled_crossing_count"] = s.modelled_crossing_count;
  j["step_count"] = s.step_count;
  j["dt_s"] = s.dt_s;
  j["dt_factor"] = scene.solver.dt_factor;
  j["contact_iterations"] = scene.solver.contact_iterations;
  j["end_time_s"] = s.end_time_s;
  j["wall_time_s"] = s.wall_time_s;
  j["node_steps_per_s"] = s.node_steps_per_s;
  j["broken_warp_elements"] = s.broken_warp;
  j["broken_weft_elements"] = s.broken_weft;
  j["broken_warp_yarns"] = s.broken_warp_yarns;
  j["broken_weft_yarns"] = s.broken_weft_yarns;
  j["broken_warp_lines"] = s.broken_warp_lines;
  j["broken_weft_lines"] = s.broken_weft_lines;
  j["max_strain"] = s.max_strain;
  j["warnings"] = s.warnings;
  return j.dump(2) + "\n";
}

void write_run_outputs(const std::string& dir, const Simulation& sim) {
  write_file_atomic(dir + "/history.csv", history_csv(sim.history()));
  write_file_atomic(dir + "/scene.toml", scene_to_toml(sim.scene()));
  // summary.json last: its presence marks a finished case (sweeps rely on it).
  write_file_atomic(dir + "/summary.json", summary_json(sim.summary(), sim.scene()));
}

}  // namespace ravel

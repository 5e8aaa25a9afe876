#include "run_record.h"

#include <filesystem>

#include "sweep.h"

namespace ravel::studies {

double RunRecord::number(const char* key, double absent) const {
  if (!json.is_object()) return absent;
  const auto it = json.find(key);
  return it != json.end() && it->is_number() ? it->get<double>() : absent;
}

RunRecord parse_run_record(const std::string& text) {
  RunRecord r;
  r.json = nlohmann::ordered_json::parse(text, nullptr, false);
  if (r.json.is_discarded()) {
    r.json = nlohmann::ordered_json();
    r.error = "unreadable (not JSON)";
    return r;
  }
  if (!r.json.is_object()) {
    r.error = "not a JSON object";
    return r;
  }
  r.ok = true;
  auto text_of = [&](const char* k) {
    const auto it = r.json.find(k);
    return it != r.json.end() && it->is_string() ? it->get<std::string>() : std::string();
  };
  r.status = text_of("status");
  r.end_reason = text_of("end_reason");
  r.diagnosis = text_of("diagnosis");
  r.divergence_cause = text_of("divergence_cause");
  const auto p = r.json.find("perforated");
  r.perforated = p != r.json.end() && p->is_boolean() && p->get<bool>();
  r.residual_velocity_mps = r.number("residual_velocity_mps");
  r.energy_absorbed_J = r.number("energy_absorbed_J");
  r.perforation_time_s = r.number("perforation_time_s", -1.0);
  r.wall_time_s = r.number("wall_time_s");
  r.node_steps_per_s = r.number("node_steps_per_s");
  r.dt_s = r.number("dt_s");
  r.step_count = r.number("step_count");
  const auto w = r.json.find("warnings");
  if (w != r.json.end() && w->is_array())
    for (const auto& t : *w)
      if (t.is_string()) r.warnings.push_back(t.get<std::string>());
  return r;
}

RunRecord read_run_record(const std::string& dir) {
  const std::string path = dir + "/summary.json";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    RunRecord r;
    r.error = "missing";
    return r;
  }
  try {
    return parse_run_record(read_text_file(path));
  } catch (const std::exception& e) {
    RunRecord r;
    r.error = std::string("unreadable (") + e.what() + ")";
    return r;
  }
}

}  // namespace ravel::studies

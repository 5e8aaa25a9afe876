// A finished run's record, read back: the one reader of the summary.json that
// core/results.h's summary_json() writes, for every study (sweep rows, the sweep panel's
// live table, stability cells, tradeoff rows, the sweep command's progress lines). The
// keys the studies use are typed here, with an absent or null value as NaN (numbers), -1
// (perforation time: none) or "" (text); the whole object stays in `json` for the rest.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace ravel::studies {

struct RunRecord {
  bool ok = false;     // read and parsed as a JSON object
  std::string error;   // why not ("missing", "unreadable (...)", "not a JSON object")
  std::string status;  // completed | diverged | interrupted | running | paused
  std::string end_reason, diagnosis, divergence_cause;
  bool perforated = false;
  double residual_velocity_mps = NAN, energy_absorbed_J = NAN;
  double perforation_time_s = -1;  // -1: did not perforate
  double wall_time_s = NAN, node_steps_per_s = NAN;
  double dt_s = NAN, step_count = NAN;
  std::vector<std::string> warnings;
  nlohmann::ordered_json json;  // the whole record, in its written key order

  // Any numeric key, `absent` when it is missing, null or not a number.
  double number(const char* key, double absent = NAN) const;
};

RunRecord parse_run_record(const std::string& text);
// DIR/summary.json; ok = false (and why in `error`) when it is missing or unreadable.
RunRecord read_run_record(const std::string& dir);

}  // namespace ravel::studies

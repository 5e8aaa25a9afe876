#include "sweep_runner.h"

#include <nlohmann/json.hpp>

#include "results.h"
#include "run_record.h"

namespace ravel::studies {

SweepRunner::~SweepRunner() {
  cancel();
  if (thread_.joinable()) thread_.join();
}

void SweepRunner::cancel() {
  interrupt_.store(true);
}

bool SweepRunner::running() const {
  std::lock_guard<std::mutex> lock(mu_);
  return state_.running;
}

SweepRunner::Snapshot SweepRunner::snapshot() const {
  std::lock_guard<std::mutex> lock(mu_);
  return state_;
}

bool SweepRunner::start(const SweepOptions& options, const std::vector<std::string>& vary_text, std::string* error,
                        int repeats) {
  if (running()) {
    if (error) *error = "a sweep is already running";
    return false;
  }
  if (thread_.joinable()) thread_.join();
  std::vector<Vary> vary;
  std::vector<std::string> keys;
  std::map<std::string, std::string> base_of;
  try {
    if (vary_text.empty()) throw StudyError("--vary: give at least one key to vary");
    for (const auto& v : vary_text) {
      vary.push_back(parse_vary(v, options.scene_path, options.overrides));
      keys.push_back(vary.back().key);
    }
    if (repeats != 1) apply_repeats(vary, repeats, &base_of);
    load_scene(options.scene_path, options.overrides);
  } catch (const std::exception& e) {
    if (error) *error = e.what();
    return false;
  }
  const auto all = expand_cases(vary);
  const auto to_run = shard_cases(all, options.shard);
  {
    std::lock_guard<std::mutex> lock(mu_);
    state_ = Snapshot{};
    state_.running = true;
    state_.varied_keys = keys;
    state_.repeats = repeats;
    state_.base_of = base_of;
    state_.progress.total = int(to_run.size());
    state_.results.header = {"case"};
    for (const auto& k : keys) state_.results.header.push_back(k);
  }
  interrupt_.store(false);
  thread_ = std::thread([this, options, all, to_run, keys, base_of, repeats] {
    SweepHooks hooks;
    // Called under the sweep's own lock, one at a time; ours is held only to copy.
    hooks.on_progress = [this](const SweepProgress& p) {
      std::lock_guard<std::mutex> lock(mu_);
      state_.progress = p;
    };
    hooks.on_case = [this, &options, &keys](const CaseResult& r) {
      if (!r.ok) return;
      const RunRecord rec = r.summary_json_text.empty() ? read_run_record(case_dir(options.out_dir, r.c))
                                                        : parse_run_record(r.summary_json_text);
      if (!rec.ok) return;
      const auto& j = rec.json;
      std::lock_guard<std::mutex> lock(mu_);
      Csv& csv = state_.results;
      if (csv.header.size() == 1 + keys.size())  // first case: the summary's scalar keys
        for (auto it = j.begin(); it != j.end(); ++it)
          if (!it.value().is_array() && !it.value().is_object()) csv.header.push_back(it.key());
      std::vector<std::string> row{r.c.name()};
      for (const auto& [k, v] : r.c.settings) row.push_back(v);
      for (size_t i = 1 + keys.size(); i < csv.header.size(); ++i) {
        const auto& v = j.contains(csv.header[i]) ? j[csv.header[i]] : nlohmann::ordered_json();
        row.push_back(v.is_string() ? v.get<std::string>() : v.is_null() ? "" : v.dump());
      }
      csv.rows.push_back(row);
    };
    SweepReport rep;
    std::string err;
    try {
      rep = run_sweep(all, to_run, options, keys, hooks, &interrupt_);
      // The perforation probability (or the removal of a stale table), from results.csv as
      // the command reads it; the app shows the same table from its own rows.
      if (!rep.interrupted)
        write_perforation_outputs(options.out_dir, parse_csv(read_text_file(options.out_dir + "/results.csv")), keys,
                                  base_of, repeats);
    } catch (const std::exception& e) {
      err = e.what();
    }
    std::lock_guard<std::mutex> lock(mu_);
    state_.report = rep;
    state_.error = err;
    state_.running = false;
    state_.finished = err.empty();
  });
  return true;
}

}  // namespace ravel::studies

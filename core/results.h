// Writing results: history.csv, summary.json, and the atomic-file helper every output
// of ravel goes through (write to a temporary name in the same folder, then rename, so
// a reader never sees half a file and an interrupted run never leaves one).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "simulation.h"

namespace ravel {

class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Create `dir` (and parents) if needed and check that it is a writable folder.
void prepare_output_dir(const std::string& dir);
// Write `content` to `path` atomically. Throws OutputError naming the path.
void write_file_atomic(const std::string& path, const std::string& content);
// The same for writers that report errors as a bool: false, and the message in *error.
bool write_file_atomic(const std::string& path, const std::string& content, std::string* error);

// `text` (a scene name, say) made safe as one file name inside an output folder: letters,
// digits, '.', '-' and '_' kept, anything else (a '/', '..', spaces) replaced by '_', no
// leading '.', at most 80 characters; "scene" when nothing is left.
std::string safe_file_name(const std::string& text);
// A short stable tag of `text` (8 hex digits of its FNV-1a hash): tells apart files made
// from different overrides.
std::string short_hash(const std::string& text);

// Grid lines (ascending, as Summary::broken_*_lines) written as ranges: "-4..4",
// "-6..-4, 0, 4..6"; "" when there are none.
std::string line_ranges(const std::vector<int>& lines);

// The column names of history.csv, in order (t_s first).
std::vector<std::string> history_columns();
std::string history_csv(const std::vector<HistoryRow>& rows);
std::string summary_json(const Summary& s, const Scene& scene);

// Write DIR/history.csv, DIR/summary.json and DIR/scene.toml (the scene as run).
void write_run_outputs(const std::string& dir, const Simulation& sim);

}  // namespace ravel

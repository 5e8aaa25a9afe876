// The studies' one pool of worker threads. A sweep's cases, the paper's and a tradeoff's
// ballistic-limit searches all run through it, so that --jobs, Ctrl-C and resuming behave
// the same in every study:
//   - `jobs` threads (at most one per item) take the items in `order`;
//   - an item with a parent (`after[i]`) is taken only once its parent has finished (the
//     paper's search tree: a search starts from its parent's limit), so the results do not
//     depend on --jobs or on which item finished first;
//   - once `interrupt` is set no item is taken; items already running see the same flag and
//     stop themselves, keeping what finished (a rerun skips what is on disk: resuming is the
//     items' own check, e.g. a case folder with its summary.json);
//   - an exception thrown by an item stops the queue like an interrupt and is rethrown by
//     run_queue once every thread has stopped (items catch what they can report themselves).
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <vector>

namespace ravel::studies {

constexpr std::size_t kNoParent = static_cast<std::size_t>(-1);

// Runs work(i) once for each item i in [0, count) on min(jobs, count) threads (jobs < 1
// counts as 1) and returns when every item has run or the queue stopped. `order` (empty:
// 0, 1, ...) must list every item once; `after` (empty: no parents) holds each item's parent
// or kNoParent, and a parent must come before its children in `order`. Throws
// std::invalid_argument for an order or a tree that breaks these rules, before running
// anything.
void run_queue(std::size_t count, int jobs, const std::atomic<bool>* interrupt,
               const std::function<void(std::size_t)>& work, const std::vector<std::size_t>& order = {},
               const std::vector<std::size_t>& after = {});

}  // namespace ravel::studies

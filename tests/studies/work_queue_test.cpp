// The studies' one work queue (studies/work_queue.h): each item once, at most `jobs` at a
// time, children after their parents, nothing new after an interrupt or an item's exception,
// and a bad order or tree refused before anything runs.
#include "work_queue.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace ravel::studies {
namespace {

using std::chrono::milliseconds;

// A log of item starts and finishes, in the order they happened.
struct Log {
  std::mutex mu;
  std::vector<std::pair<char, size_t>> events;  // ('s' | 'f', item)
  int running = 0, most_running = 0;
  void start(size_t i) {
    std::lock_guard<std::mutex> lock(mu);
    events.push_back({'s', i});
    most_running = std::max(most_running, ++running);
  }
  // Waits (up to 10 s, so a broken queue fails instead of hanging) until `pred` holds.
  template <class Pred>
  bool wait_until(Pred pred) {
    for (int k = 0; k < 10000; ++k) {
      {
        std::lock_guard<std::mutex> lock(mu);
        if (pred()) return true;
      }
      std::this_thread::sleep_for(milliseconds(1));
    }
    return false;
  }
  void finish(size_t i) {
    std::lock_guard<std::mutex> lock(mu);
    events.push_back({'f', i});
    --running;
  }
  long at(char kind, size_t i) const {
    for (size_t k = 0; k < events.size(); ++k)
      if (events[k] == std::make_pair(kind, i)) return long(k);
    return -1;
  }
  std::vector<size_t> started() const {
    std::vector<size_t> s;
    for (const auto& e : events)
      if (e.first == 's') s.push_back(e.second);
    return s;
  }
};

TEST(WorkQueue, RunsEachItemOnceOnAtMostJobsThreads) {
  Log log;
  std::mutex mu;
  std::set<std::thread::id> threads;
  std::vector<int> runs(20, 0);
  run_queue(20, 3, nullptr, [&](size_t i) {
    log.start(i);
    {
      std::lock_guard<std::mutex> lock(mu);
      threads.insert(std::this_thread::get_id());
      ++runs[i];
    }
    // The first item waits for a second one to run beside it.
    if (i == 0) {
      EXPECT_TRUE(log.wait_until([&] { return log.started().size() >= 2; })) << "no item ran beside the first";
    }
    log.finish(i);
  });
  for (size_t i = 0; i < runs.size(); ++i) EXPECT_EQ(runs[i], 1) << "item " << i;
  EXPECT_LE(threads.size(), 3u);
  EXPECT_LE(log.most_running, 3);
  EXPECT_GE(log.most_running, 2);
}

// The paper's search tree: a search starts only once the one it starts from has finished,
// whatever the number of jobs; the ones that do not depend on each other run side by side.
TEST(WorkQueue, ChildrenStartAfterTheirParentsFinish) {
  //   0 -> 1 -> 3 -> 4,  0 -> 2,  5 (a second root)
  const std::vector<size_t> order = {0, 1, 2, 3, 4, 5};
  const std::vector<size_t> after = {kNoParent, 0, 0, 1, 3, kNoParent};
  for (int jobs : {1, 2, 4}) {
    Log log;
    auto work = [&](size_t i) {
      log.start(i);
      // With more than one job the other root (5) is taken while 0 runs, not after it.
      if (i == 0 && jobs > 1) {
        EXPECT_TRUE(log.wait_until([&] { return log.at('s', 5) >= 0; })) << "5 waited for 0, " << jobs << " jobs";
      }
      std::this_thread::sleep_for(milliseconds(2));
      log.finish(i);
    };
    run_queue(6, jobs, nullptr, work, order, after);
    ASSERT_EQ(log.events.size(), 12u) << jobs << " jobs";
    for (size_t i = 0; i < after.size(); ++i) {
      if (after[i] != kNoParent) {
        EXPECT_GT(log.at('s', i), log.at('f', after[i]))
            << "item " << i << " started before its parent, " << jobs << " jobs";
      }
    }
    if (jobs == 1) {
      EXPECT_EQ(log.started(), order);
    }
  }
}

TEST(WorkQueue, OneJobFollowsTheOrderGiven) {
  Log log;
  const std::vector<size_t> order = {3, 0, 2, 1};
  run_queue(
      4, 1, nullptr, [&](size_t i) { log.start(i); }, order);
  EXPECT_EQ(log.started(), order);
}

// Ctrl-C: the item running sees the flag itself; no item is taken after it.
TEST(WorkQueue, TakesNothingAfterAnInterrupt) {
  std::atomic<bool> interrupt{false};
  Log log;
  run_queue(10, 1, &interrupt, [&](size_t i) {
    log.start(i);
    if (i == 3) interrupt = true;
  });
  EXPECT_EQ(log.started(), (std::vector<size_t>{0, 1, 2, 3}));
  // A child waiting for a parent that the interrupt stopped returns too (does not hang).
  interrupt = false;
  Log tree;
  run_queue(3, 2, &interrupt,
            [&](size_t i) {
              tree.start(i);
              if (i == 0) {
                std::this_thread::sleep_for(milliseconds(50));
                interrupt = true;
              }
            },
            {0, 1, 2}, {kNoParent, 0, 1});
  EXPECT_EQ(tree.started(), (std::vector<size_t>{0}));
}

TEST(WorkQueue, AnItemsExceptionStopsTheQueueAndIsRethrown) {
  Log log;
  EXPECT_THROW(run_queue(6, 1, nullptr,
                         [&](size_t i) {
                           log.start(i);
                           if (i == 2) throw std::runtime_error("disk full");
                         }),
               std::runtime_error);
  EXPECT_EQ(log.started(), (std::vector<size_t>{0, 1, 2}));
}

TEST(WorkQueue, RefusesABadOrderOrTreeBeforeRunningAnything) {
  int runs = 0;
  auto work = [&](size_t) { ++runs; };
  EXPECT_THROW(run_queue(3, 1, nullptr, work, {0, 1}), std::invalid_argument);     // an item left out
  EXPECT_THROW(run_queue(3, 1, nullptr, work, {0, 1, 1}), std::invalid_argument);  // listed twice
  EXPECT_THROW(run_queue(3, 1, nullptr, work, {0, 1, 7}), std::invalid_argument);  // no such item
  EXPECT_THROW(run_queue(3, 1, nullptr, work, {1, 0, 2}, {kNoParent, 0, 1}), std::invalid_argument);  // child first
  EXPECT_THROW(run_queue(2, 1, nullptr, work, {}, {1, 0}), std::invalid_argument);                    // a cycle
  EXPECT_EQ(runs, 0);
  run_queue(0, 2, nullptr, work);  // nothing to do
  EXPECT_EQ(runs, 0);
}

}  // namespace
}  // namespace ravel::studies

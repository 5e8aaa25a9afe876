#include "work_queue.h"

#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace ravel::studies {

void run_queue(std::size_t count, int jobs, const std::atomic<bool>* interrupt,
               const std::function<void(std::size_t)>& work, const std::vector<std::size_t>& order_in,
               const std::vector<std::size_t>& after) {
  if (count == 0) return;
  std::vector<std::size_t> order = order_in;
  if (order.empty())
    for (std::size_t i = 0; i < count; ++i) order.push_back(i);
  if (order.size() != count)
    throw std::invalid_argument("work queue: the order lists " + std::to_string(order.size()) + " items, expected " +
                                std::to_string(count));
  if (!after.empty() && after.size() != count)
    throw std::invalid_argument("work queue: " + std::to_string(after.size()) + " parents for " +
                                std::to_string(count) + " items");
  std::vector<std::size_t> position(count, kNoParent);
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t i = order[k];
    if (i >= count || position[i] != kNoParent)
      throw std::invalid_argument("work queue: the order does not list each item once (item " + std::to_string(i) +
                                  ")");
    position[i] = k;
  }
  for (std::size_t i = 0; i < after.size(); ++i)
    if (after[i] != kNoParent && (after[i] >= count || position[after[i]] >= position[i]))
      throw std::invalid_argument("work queue: item " + std::to_string(i) + " comes before its parent " +
                                  std::to_string(after[i]));

  std::mutex mu;
  std::condition_variable finished_cv;  // an item finished (its children may start)
  std::vector<char> taken(count, 0), finished(count, 0);
  std::exception_ptr error;
  auto stopped = [&] { return error || (interrupt && interrupt->load()); };

  auto worker = [&] {
    for (;;) {
      std::size_t item = kNoParent;
      {
        std::unique_lock<std::mutex> lock(mu);
        for (;;) {
          if (stopped()) return;
          bool left = false;
          for (std::size_t i : order) {
            if (taken[i]) continue;
            left = true;
            if (after.empty() || after[i] == kNoParent || finished[after[i]]) {
              item = i;
              break;
            }
          }
          if (!left) return;
          if (item != kNoParent) break;
          // Every item left waits for a parent still running: wait for one to finish, waking
          // now and then to see an interrupt.
          finished_cv.wait_for(lock, std::chrono::milliseconds(200));
        }
        taken[item] = 1;
      }
      try {
        work(item);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mu);
        if (!error) error = std::current_exception();
      }
      {
        std::lock_guard<std::mutex> lock(mu);
        finished[item] = 1;
      }
      finished_cv.notify_all();
    }
  };

  const int threads = int(std::min<std::size_t>(count, std::size_t(std::max(1, jobs))));
  std::vector<std::thread> pool;
  for (int j = 0; j < threads; ++j) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace ravel::studies

#include "ctid/core/parallel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "ctid/core/error.h"

namespace ctid {
namespace {
thread_local bool parallel_worker = false;
}  // namespace

bool inside_parallel_loop() { return parallel_worker; }

int resolve_thread_count(int threads) {
  if (threads > 0) return threads;
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware == 0 ? 1 : static_cast<int>(hardware);
}

int idle_thread_count() {
  const int cores = resolve_thread_count(0);
  double load[1] = {0.0};
  if (getloadavg(load, 1) != 1 || !(load[0] >= 0.0)) return 1;
  const double idle = std::floor(static_cast<double>(cores) - load[0]);
  return std::clamp(1 + static_cast<int>(std::max(idle, 0.0)), 1, cores);
}

namespace internal {

// A barrier for the short phases of a ThreadTeam: a participant that arrives early spins for
// a while (a phase of a long fit's pass takes some tens of microseconds, and std::barrier's
// sleep and wake-up cost about as much), then sleeps on the generation counter.
class SpinBarrier {
 public:
  explicit SpinBarrier(int count) : count_(count) {}

  void arrive_and_wait() {
    const unsigned generation = generation_.load(std::memory_order_acquire);
    if (arrived_.fetch_add(1, std::memory_order_acq_rel) + 1 == count_) {
      arrived_.store(0, std::memory_order_relaxed);
      generation_.fetch_add(1, std::memory_order_release);
      generation_.notify_all();
      return;
    }
    constexpr int kSpins = 1000;
    for (int spin = 0; spin < kSpins; ++spin) {
      if (generation_.load(std::memory_order_acquire) != generation) return;
#if defined(__x86_64__) || defined(__i386__)
      __builtin_ia32_pause();
#endif
    }
    while (generation_.load(std::memory_order_acquire) == generation) {
      generation_.wait(generation, std::memory_order_acquire);
    }
  }

 private:
  const int count_;
  std::atomic<int> arrived_{0};
  std::atomic<unsigned> generation_{0};
};

}  // namespace internal

struct ThreadTeam::Shared {
  explicit Shared(int threads) : start(threads), done(threads) {}
  internal::SpinBarrier start;
  internal::SpinBarrier done;
  const std::function<void(int)>* body = nullptr;
  int count = 0;
  bool stop = false;
  std::atomic<int> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr first_error;
  std::mutex error_mutex;
  std::vector<std::thread> workers;

  // Every participant's share of one run: indices in increasing order until none is left.
  void work() {
    for (;;) {
      if (failed.load()) return;
      const int i = next.fetch_add(1);
      if (i >= count) return;
      try {
        (*body)(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!first_error) first_error = std::current_exception();
        failed.store(true);
        return;
      }
    }
  }
};

ThreadTeam::ThreadTeam(int threads) {
  require(threads >= 1, "ThreadTeam: threads is ", threads, "; it must be >= 1");
  shared_ = std::make_unique<Shared>(threads);
  Shared& s = *shared_;
  for (int t = 1; t < threads; ++t) {
    s.workers.emplace_back([&s] {
      parallel_worker = true;
      for (;;) {
        s.start.arrive_and_wait();
        if (s.stop) return;
        s.work();
        s.done.arrive_and_wait();
      }
    });
  }
}

ThreadTeam::~ThreadTeam() {
  Shared& s = *shared_;
  if (s.workers.empty()) return;
  s.stop = true;
  s.start.arrive_and_wait();
  for (std::thread& thread : s.workers) thread.join();
}

int ThreadTeam::size() const { return static_cast<int>(shared_->workers.size()) + 1; }

void ThreadTeam::run(int count, const std::function<void(int)>& body) {
  require(count >= 0, "ThreadTeam::run: count is ", count, "; it must be >= 0");
  Shared& s = *shared_;
  s.body = &body;
  s.count = count;
  s.next.store(0);
  s.failed.store(false);
  s.first_error = nullptr;
  if (s.workers.empty() || count <= 1) {
    s.work();
  } else {
    s.start.arrive_and_wait();
    s.work();
    s.done.arrive_and_wait();
  }
  if (s.first_error) std::rethrow_exception(s.first_error);
}

void parallel_for(int count, int threads, const std::function<void(int)>& body) {
  require(count >= 0, "parallel_for: count is ", count, "; it must be >= 0");
  require(threads >= 0, "parallel_for: threads is ", threads, "; it must be >= 0");
  // The caller is one of the team, and inside the loop too while it runs bodies.
  const bool was = parallel_worker;
  parallel_worker = true;
  try {
    ThreadTeam(std::min(resolve_thread_count(threads), std::max(count, 1))).run(count, body);
  } catch (...) {
    parallel_worker = was;
    throw;
  }
  parallel_worker = was;
}

}  // namespace ctid

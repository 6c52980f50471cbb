// The parallel loops' contract (core/parallel.h): every index once, an outcome that does not
// depend on the number of threads, the first exception rethrown, and workers that know they
// are inside a parallel loop. ThreadTeam is run many times in a row, as a fit's passes run it.
#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/parallel.h"

namespace ctid::parallel_test {
namespace {

TEST(ThreadTeam, RunsEveryIndexOnceInManyRunsWhateverItsSize) {
  for (const int threads : {1, 2, 3}) {
    ThreadTeam team(threads);
    EXPECT_EQ(team.size(), threads);
    for (int run = 0; run < 500; ++run) {
      const int count = run % 7;  // 0 and 1 included: the caller alone
      std::vector<int> hits(static_cast<size_t>(count), 0);
      team.run(count, [&](int i) { ++hits[static_cast<size_t>(i)]; });
      for (int i = 0; i < count; ++i) {
        ASSERT_EQ(hits[static_cast<size_t>(i)], 1) << threads << " threads, run " << run;
      }
    }
  }
}

TEST(ThreadTeam, ItsWorkersAreInsideAParallelLoopAndTheCallerIsNot) {
  ThreadTeam team(2);
  std::atomic<int> inside{0};
  std::atomic<int> outside{0};
  for (int run = 0; run < 200; ++run) {
    team.run(8, [&](int) { ++(inside_parallel_loop() ? inside : outside); });
  }
  EXPECT_EQ(inside + outside, 1600);
  EXPECT_FALSE(inside_parallel_loop());
  bool in_parallel_for = false;
  parallel_for(2, 2, [&](int i) {
    if (i == 0) in_parallel_for = inside_parallel_loop();
  });
  EXPECT_TRUE(in_parallel_for);
  in_parallel_for = false;
  parallel_for(1, 1, [&](int) { in_parallel_for = inside_parallel_loop(); });  // on the caller
  EXPECT_TRUE(in_parallel_for);
  EXPECT_FALSE(inside_parallel_loop());
}

TEST(ThreadTeam, IdleThreadCountIsBetweenOneAndEveryCore) {
  const int idle = idle_thread_count();
  EXPECT_GE(idle, 1);
  EXPECT_LE(idle, resolve_thread_count(0));
}

TEST(ThreadTeam, RethrowsTheFirstErrorAndRunsOnAfterIt) {
  ThreadTeam team(3);
  try {
    team.run(50, [](int i) {
      if (i == 17) throw std::runtime_error("index 17 failed");
    });
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "index 17 failed");
  }
  std::atomic<int> sum{0};
  team.run(10, [&](int i) { sum += i; });
  EXPECT_EQ(sum, 45);
  EXPECT_THROW(ThreadTeam(0), InvalidArgument);
}

}  // namespace
}  // namespace ctid::parallel_test

// A parallel loop whose outcome does not depend on the number of threads: indices handed out
// in increasing order, each body writing only to storage owned by its index. Studies run their
// cases with it, and the scans of the estimators (delays, structures) their fits.
#pragma once

#include <functional>

namespace ctid {

/// The worker count used for `threads`: `threads` itself if > 0, otherwise
/// std::thread::hardware_concurrency() (at least 1).
int resolve_thread_count(int threads);

/// Calls body(i) for every i in [0, count) on up to `threads` threads (0: all cores). Indices
/// are handed out in increasing order; body must write only to storage owned by index i,
/// which makes the outcome independent of the thread count. The first exception thrown by a
/// body is rethrown after all threads have stopped (remaining indices are skipped).
void parallel_for(int count, int threads, const std::function<void(int)>& body);

}  // namespace ctid

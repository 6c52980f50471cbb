// Long tests whose code paths a cheaper test of the same sanitizer run already goes through
// (a second seed, a Monte Carlo of one estimator, a scan another test also runs) skip their
// sanitizer run with CTID_SKIP_UNDER_SANITIZERS(why); the Release ctest runs them whole. The
// sanitizer build (scripts/test.sh step 3) is -O1 with assertions and 10-15 times slower, so
// these few tests were most of its time. CTID_UNDER_SANITIZERS is 1 in that build and 0 in
// the others (a test that caps a child's address space, which AddressSanitizer reserves in
// terabytes, reads it too).
#pragma once

#include <gtest/gtest.h>

#if defined(__SANITIZE_ADDRESS__)
#define CTID_UNDER_SANITIZERS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CTID_UNDER_SANITIZERS 1
#endif
#endif
#ifndef CTID_UNDER_SANITIZERS
#define CTID_UNDER_SANITIZERS 0
#endif

// Inside a TEST body: ends the test as skipped under the sanitizers, saying why.
#define CTID_SKIP_UNDER_SANITIZERS(why) \
  if (!CTID_UNDER_SANITIZERS) {         \
  } else                                \
    GTEST_SKIP() << "skipped under the sanitizers: " << (why)

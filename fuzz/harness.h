// What every reader harness checks: the reader either returns or throws ctid::InvalidArgument
// (bad input, one message). Any other exception escapes to libFuzzer, which reports it as a
// crash, as it does for the sanitizers' findings, aborts and timeouts. A harness also checks
// that what was read is written back by ctid's own writer and read again unchanged.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include "ctid/core/error.h"

namespace ctid::fuzz {

/// use(value); a refusal of bad input (InvalidArgument) is an expected outcome.
template <class Value, class Use>
void refuse_or_use(const Value& value, Use use) {
  try {
    use(value);
  } catch (const ctid::InvalidArgument&) {
  }
}

/// read_back(): what ctid wrote, ctid must read; a refusal is a finding, reported with the
/// reader's message before the abort that libFuzzer records as a crash.
template <class ReadBack>
void must_read_back(ReadBack read_back) {
  try {
    read_back();
  } catch (const ctid::InvalidArgument& e) {
    std::fprintf(stderr, "written by ctid, refused by ctid: %s\n", e.what());
    std::abort();
  }
}

/// Aborts with `what` on stderr (a property of a reader that does not hold).
[[noreturn]] inline void finding(const char* what) {
  std::fprintf(stderr, "%s\n", what);
  std::abort();
}

/// read(text) on the fuzzer's bytes.
template <class Read>
int refuse_or_read(const std::uint8_t* data, std::size_t size, Read read) {
  refuse_or_use(std::string_view(reinterpret_cast<const char*>(data), size), read);
  return 0;
}

}  // namespace ctid::fuzz

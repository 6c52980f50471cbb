#include "ctid/refined_iv/refined_iv_options.h"

#include <charconv>
#include <string>

#include "ctid/core/error.h"

namespace ctid {

namespace {

// A whole number 0..kMaxArmaOrder spelt in full, or none.
std::optional<int> noise_order_word(std::string_view text) {
  int value = 0;
  const char* end = text.data() + text.size();
  const auto [at, error] = std::from_chars(text.data(), end, value);
  if (text.empty() || error != std::errc() || at != end || value < 0 || value > 20) {
    return std::nullopt;
  }
  return value;
}

}  // namespace

std::optional<NoiseModelOrders> NoiseModelOrders::from_flag(std::string_view word) {
  if (word == "none") return std::nullopt;
  NoiseModelOrders orders;
  if (word == "auto") {
    orders.automatic = true;
    return orders;
  }
  const std::size_t comma = word.find(',');
  const std::optional<int> ar =
      comma == std::string_view::npos ? std::nullopt : noise_order_word(word.substr(0, comma));
  const std::optional<int> ma =
      comma == std::string_view::npos ? std::nullopt : noise_order_word(word.substr(comma + 1));
  require(ar && ma, "the noise model '", std::string(word),
          "' is not P,Q (the AR and MA orders, each a whole number from 0 to 20), auto or none");
  orders.ar = *ar;
  orders.ma = *ma;
  return orders;
}

}  // namespace ctid

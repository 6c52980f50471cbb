// How text read from a user's file is echoed in a message.
#pragma once

#include <string>
#include <string_view>

namespace ctid::io::internal {

// A field as it is echoed in a message: control bytes escaped (\x0d), and cut after 80
// characters with the full length stated, so a binary or huge field keeps the message one
// readable line.
inline std::string echo(std::string_view field) {
  constexpr size_t kShown = 80;
  std::string out;
  for (size_t i = 0; i < field.size() && i < kShown; ++i) {
    const auto c = static_cast<unsigned char>(field[i]);
    if (c < 0x20 || c == 0x7f) {
      constexpr char kHex[] = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (field.size() > kShown) out += "... (" + std::to_string(field.size()) + " bytes)";
  return out;
}

}  // namespace ctid::io::internal

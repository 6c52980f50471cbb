// The output convention of docs/conventions.md ("What ctid prints") as a check on text ctid
// printed: convention_violations(text) lists every place that breaks it, empty when none does.
// Used on every message of the bad-input catalogue (catalogue_test.cc) and on the summaries of
// successful runs (conventions_test.cc). Text inside single quotes is the user's own, echoed
// back, and is not checked.
#pragma once

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <string>
#include <vector>

#include "ctid/core/format.h"

namespace ctid::cli::testing {

namespace detail {

inline bool word_character(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
}

// `text` with every '...' span (the user's words shown back) blanked.
inline std::string without_quotes(const std::string& text) {
  std::string out = text;
  bool inside = false;
  for (std::size_t k = 0; k < out.size(); ++k) {
    // An apostrophe inside a word ("don't", "window's") opens nothing.
    const bool apostrophe = out[k] == '\'' && k > 0 && word_character(text[k - 1]) &&
                            k + 1 < out.size() && word_character(text[k + 1]);
    if (out[k] == '\'' && !apostrophe) {
      inside = !inside;
    } else if (inside && out[k] != '\n') {
      out[k] = ' ';
    }
  }
  return out;
}

inline std::string line_around(const std::string& text, std::size_t at) {
  const std::size_t begin = text.rfind('\n', at);
  const std::size_t end = text.find('\n', at);
  return text.substr(begin == std::string::npos ? 0 : begin + 1,
                     (end == std::string::npos ? text.size() : end) -
                         (begin == std::string::npos ? 0 : begin + 1));
}

}  // namespace detail

/// Every break of the printed-output convention in `text`, one line each:
///   - polynomials in s (continuous time), never in p: no "p^" and no " p " term;
///   - no power written as ^1, and an integrator's factor is not glued to A's terms
///     ("s^1 0.000224 s^2");
///   - things a person counts are numbered from 1: no "submodel 0", "mode 0", "output 0",
///     "input 0", "record 0", "experiment 0", "window 0", "file 0";
///   - numbers in format.h's forms: never std::to_string's six fixed decimals ("0.500000"),
///     and no more than 12 significant digits unless that is the shortest text of the value
///     ("0.10000000000000001" is not).
inline std::vector<std::string> convention_violations(const std::string& printed) {
  std::vector<std::string> found;
  const std::string text = detail::without_quotes(printed);
  const auto report = [&](std::size_t at, const std::string& rule) {
    found.push_back(rule + ": " + detail::line_around(printed, at));
  };
  for (const char* form : {"p^", " p + ", " p - ", " p)", "(p ", "^1 ", "^1)"}) {
    for (std::size_t at = text.find(form); at != std::string::npos; at = text.find(form, at + 1)) {
      report(at, std::string("polynomial form '") + form + "'");
    }
  }
  for (const char* thing : {"submodel 0", "mode 0", "output 0", "input 0", "record 0",
                            "experiment 0", "window 0", "file 0"}) {
    const std::string word(thing);
    for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) {
      const std::size_t after = at + word.size();
      const bool whole =
          (at == 0 || !detail::word_character(text[at - 1])) &&
          (after == text.size() || (!detail::word_character(text[after]) && text[after] != '.'));
      if (whole) report(at, "counted from 0 ('" + word + "')");
    }
  }
  // Numbers: a digit run with at most one '.', then an optional exponent.
  for (std::size_t k = 0; k < text.size();) {
    const bool starts = std::isdigit(static_cast<unsigned char>(text[k])) != 0 &&
                        (k == 0 || (!detail::word_character(text[k - 1]) && text[k - 1] != '.'));
    if (!starts) {
      ++k;
      continue;
    }
    std::size_t end = k;
    int dots = 0;
    while (end < text.size() &&
           (std::isdigit(static_cast<unsigned char>(text[end])) != 0 || text[end] == '.')) {
      dots += text[end] == '.' ? 1 : 0;
      ++end;
    }
    std::string mantissa = text.substr(k, end - k);
    while (!mantissa.empty() && mantissa.back() == '.') {  // a sentence's full stop
      mantissa.pop_back();
      --dots;
    }
    std::size_t token_end = k + mantissa.size();
    if (token_end < text.size() && (text[token_end] == 'e' || text[token_end] == 'E')) {
      std::size_t e = token_end + 1;
      if (e < text.size() && (text[e] == '+' || text[e] == '-')) ++e;
      if (e < text.size() && std::isdigit(static_cast<unsigned char>(text[e])) != 0) {
        while (e < text.size() && std::isdigit(static_cast<unsigned char>(text[e])) != 0) ++e;
        token_end = e;
      }
    }
    const bool word_follows = token_end < text.size() && detail::word_character(text[token_end]);
    if (dots == 1 && !word_follows) {
      const std::string token = text.substr(k, token_end - k);
      // std::to_string's six fixed decimals ("0.500000"); a table's fixed decimals
      // (format_fixed: "92.77", "1.0000") are allowed.
      const std::size_t point = mantissa.find('.');
      if (mantissa.size() - point - 1 == 6 && mantissa.back() == '0') {
        report(k, "std::to_string's six decimals in '" + token + "'");
      }
      int significant = 0;
      bool leading = true;
      for (const char c : mantissa) {
        if (c == '.') continue;
        if (leading && c == '0') continue;
        leading = false;
        ++significant;
      }
      if (significant > 12 && format_round_trip(std::strtod(token.c_str(), nullptr)) != token) {
        report(k, "more digits than the value needs in '" + token + "'");
      }
    }
    k = std::max(end, token_end);
  }
  return found;
}

}  // namespace ctid::cli::testing

// Universal file dataset 58 (FRF records) read into and written from a MimoFrf (uff58.h). The
// record layout is the one of the I-DEAS universal file format documentation for dataset 58
// (records 1-5 ID lines, 6 the function and its response/reference node and direction, 7 the
// data form, 8-11 the axes' characteristics, 12 the values).
#include "ctid/io/uff58.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "ctid/core/error.h"
#include "io/internal/echo.h"

namespace ctid::io {

namespace {

std::string trim(std::string_view text) {
  std::size_t b = 0;
  std::size_t e = text.size();
  while (b < e && std::isspace(static_cast<unsigned char>(text[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(text[e - 1]))) --e;
  return std::string(text.substr(b, e - b));
}

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

std::optional<long> to_int(const std::string& text) {
  const std::string t = trim(text);
  if (t.empty()) return std::nullopt;
  std::size_t used = 0;
  try {
    const long v = std::stol(t, &used);
    if (used == t.size()) return v;
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::optional<double> to_double(std::string t) {
  std::replace(t.begin(), t.end(), 'D', 'E');
  std::replace(t.begin(), t.end(), 'd', 'e');
  // from_chars, not stod: stod follows LC_NUMERIC, which Python may have set to a comma
  // locale (issue 33). The field is one number: no blanks, an optional leading '+'.
  std::string_view digits = t;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  if (digits.empty() || digits.front() == '+') return std::nullopt;
  double v = 0.0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
  if (error == std::errc() && end == digits.data() + digits.size() && std::isfinite(v)) return v;
  return std::nullopt;
}

// printf's "%<width>.<precision>E" of the C locale whatever LC_NUMERIC says (snprintf wrote
// "1,00000E+00" under a comma locale set in Python, issue 33).
std::string format_e(double x, int width, int precision) {
  char buffer[64];
  const auto written =
      std::to_chars(buffer, buffer + sizeof buffer, x, std::chars_format::scientific, precision);
  std::string text(buffer, written.ptr);
  for (char& c : text) {
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');  // e, inf, nan
  }
  if (static_cast<int>(text.size()) < width) text.insert(0, width - text.size(), ' ');
  return text;
}

std::string function_type_name(long type) {
  switch (type) {
    case 0:
      return "general or unknown";
    case 1:
      return "time response";
    case 2:
      return "auto spectrum";
    case 3:
      return "cross spectrum";
    case 4:
      return "frequency response function";
    case 5:
      return "transmissibility";
    case 6:
      return "coherence";
    case 9:
      return "power spectral density";
    case 12:
      return "spectrum";
    case 26:
      return "multiple coherence";
    default:
      return "type " + std::to_string(type);
  }
}

const char* const kDirections[] = {"X", "Y", "Z", "RX", "RY", "RZ"};
// Record 6 holds each node in an I10 field: -999999999 to 9999999999.
constexpr std::size_t kNodeDigits = 10;
constexpr long kLargestNode = 9'999'999'999;
constexpr long kSmallestNode = -999'999'999;

std::string channel_name(long node, long direction) {
  if (direction == 0) return std::to_string(node);
  return std::to_string(node) + (direction > 0 ? "+" : "-") + kDirections[std::abs(direction) - 1];
}

struct Channel {
  long node = 0;
  long direction = 0;
};

// "<node><sign><direction>" or "<node>": digits, then optionally + or - and one of
// kDirections. (Parsed by hand: GCC 12 warns inside std::regex under the sanitizer build.)
std::optional<Channel> channel_of(const std::string& name) {
  std::size_t digits = 0;
  while (digits < name.size() && name[digits] >= '0' && name[digits] <= '9') ++digits;
  // A node fills an I10 field of record 6: at most 10 digits, or the writer's line shifts.
  if (digits == 0 || digits > kNodeDigits) return std::nullopt;
  Channel c{std::stol(name.substr(0, digits)), 0};
  if (digits == name.size()) return c;
  const char sign = name[digits];
  if (sign != '+' && sign != '-') return std::nullopt;
  const std::string direction = name.substr(digits + 1);
  for (long d = 0; d < 6; ++d) {
    if (direction == kDirections[d]) c.direction = sign == '-' ? -(d + 1) : d + 1;
  }
  if (c.direction == 0) return std::nullopt;
  return c;
}

// The node and direction each name is written with: its own where it is one (channel_of) and
// not taken by an earlier name (e.g. "1" and "01"), otherwise the first node from `first` on
// that no channel of the list uses, scalar. So every channel of a list gets its own pair and
// the file reads back (a name "1" beside an unparsable one numbered 1 was written twice).
std::vector<Channel> channels_of(const std::vector<std::string>& names, long first) {
  std::vector<std::optional<Channel>> own;
  std::set<std::pair<long, long>> used;
  for (const std::string& name : names) {
    std::optional<Channel> c = channel_of(name);
    if (c && !used.insert({c->node, c->direction}).second) c.reset();
    own.push_back(c);
  }
  std::vector<Channel> out;
  long next = first;
  for (const std::optional<Channel>& c : own) {
    if (c) {
      out.push_back(*c);
      continue;
    }
    while (used.count({next, 0}) > 0) ++next;
    used.insert({next, 0});
    out.push_back({next, 0});
  }
  return out;
}

struct Record {
  std::string output;
  std::string input;
  Eigen::VectorXd frequencies;  // rad/s
  Eigen::VectorXcd values;
  int line = 0;
};

// One dataset 58 whose first body line (ID line 1) is line `first` (1-based) of the file.
Record parse_record(const std::vector<std::string>& body, int first, const std::string& source) {
  const std::string where = ctid::internal::concat(source, ": dataset 58 at line ", first - 1);
  require(body.size() >= 11, where, ": ", body.size(),
          " lines before the closing -1; a dataset 58 has 11 header records before its data");
  // Record 6: (2(I5,I10),2(1X,10A,I10,I4)).
  const std::string& r6 = body[5];
  const auto column = [&](std::size_t at, std::size_t width) {
    return at < r6.size() ? r6.substr(at, width) : std::string();
  };
  std::optional<long> type = to_int(column(0, 5));
  std::optional<long> response_node = to_int(column(41, 10));
  std::optional<long> response_direction = to_int(column(51, 4));
  std::optional<long> reference_node = to_int(column(66, 10));
  std::optional<long> reference_direction = to_int(column(76, 4));
  if (!type || !response_node || !response_direction || !reference_node || !reference_direction) {
    // Not in the fixed columns: the ten fields separated by spaces.
    const std::vector<std::string> t = tokens(r6);
    require(t.size() == 10, where, ", record 6 (line ", first + 5, "): '", internal::echo(trim(r6)),
            "' is not the function type, identification, version, load case, response entity, "
            "node, direction, reference entity, node and direction");
    type = to_int(t[0]);
    response_node = to_int(t[5]);
    response_direction = to_int(t[6]);
    reference_node = to_int(t[8]);
    reference_direction = to_int(t[9]);
    require(type && response_node && response_direction && reference_node && reference_direction,
            where, ", record 6 (line ", first + 5, "): '", internal::echo(trim(r6)),
            "' has a field that is not an integer");
  }
  require(*type == 4, where, ": function type ", *type, " (", function_type_name(*type),
          ") is not an FRF; only function type 4 (frequency response function) is read");
  for (long node : {*response_node, *reference_node}) {
    require(node >= kSmallestNode && node <= kLargestNode, where, ", record 6: node ", node,
            " does not fit the 10 columns of its field (", kSmallestNode, " to ", kLargestNode,
            ")");
  }
  for (long d : {*response_direction, *reference_direction}) {
    require(std::abs(d) <= 6, where, ", record 6: direction ", d,
            " is not one of 0 (scalar), +-1..+-3 (X, Y, Z) or +-4..+-6 (RX, RY, RZ)");
  }
  // Record 7: (3I10,3E13.5).
  const std::vector<std::string> r7 = tokens(body[6]);
  require(r7.size() >= 5, where, ", record 7 (line ", first + 6, "): '",
          internal::echo(trim(body[6])),
          "' is not the ordinate type, the number of values, the spacing, the abscissa minimum "
          "and increment");
  const std::optional<long> ordinate = to_int(r7[0]);
  const std::optional<long> count = to_int(r7[1]);
  const std::optional<long> spacing = to_int(r7[2]);
  const std::optional<double> minimum = to_double(r7[3]);
  const std::optional<double> increment = to_double(r7[4]);
  require(ordinate && count && spacing && minimum && increment, where, ", record 7 (line ",
          first + 6, "): '", internal::echo(trim(body[6])), "' has a field that is not a number");
  require(*ordinate == 5 || *ordinate == 6, where, ": ordinate data type ", *ordinate,
          " is not complex; only 5 (complex single) and 6 (complex double) are read");
  require(*spacing == 0 || *spacing == 1, where, ": abscissa spacing ", *spacing,
          " is neither 0 (uneven) nor 1 (even)");
  require(*count >= 1, where, ": ", *count, " values; a record needs at least one");
  // Record 8: the abscissa must be a frequency (18), or unknown (0) taken as Hz.
  const std::vector<std::string> r8 = tokens(body[7]);
  const long abscissa = r8.empty() ? -1 : to_int(r8[0]).value_or(-1);
  require(abscissa == 18 || abscissa == 0, where, ", record 8 (line ", first + 7,
          "): the abscissa's specific data type is '",
          internal::echo(r8.empty() ? std::string_view() : std::string_view(r8[0])),
          "'; only 18 (frequency, in Hz) or 0 (unknown, taken as Hz) are read");
  std::vector<double> values;
  for (std::size_t q = 11; q < body.size(); ++q) {
    for (const std::string& t : tokens(body[q])) {
      const std::optional<double> v = to_double(t);
      require(v.has_value(), where, ", record 12 (line ", first + static_cast<int>(q), "): '",
              internal::echo(t), "' is not a finite number");
      values.push_back(*v);
    }
  }
  const std::size_t per = *spacing == 1 ? 2 : 3;
  require(values.size() == per * static_cast<std::size_t>(*count), where, ": record 12 holds ",
          values.size(), " numbers but record 7 announces ", *count, " ",
          *spacing == 1 ? "complex values (2 numbers each)"
                        : "abscissa/complex pairs (3 numbers each)");
  Record r;
  r.line = first - 1;
  r.output = channel_name(*response_node, *response_direction);
  r.input = channel_name(*reference_node, *reference_direction);
  r.frequencies.resize(*count);
  r.values.resize(*count);
  for (long i = 0; i < *count; ++i) {
    const std::size_t at = per * static_cast<std::size_t>(i);
    const double hz = *spacing == 1 ? *minimum + static_cast<double>(i) * *increment : values[at];
    r.frequencies(i) = 2.0 * std::numbers::pi * hz;
    r.values(i) = {values[at + per - 2], values[at + per - 1]};
  }
  return r;
}

bool is_delimiter(const std::string& line) { return trim(line) == "-1"; }

// Record 1, the free-text ID line, as the writer fills it: the channel names with their control
// bytes escaped (\x00, \x0a: a NUL or a line break in a name would otherwise be written into
// the file, and a line break shifts every record after it), at most 80 characters.
std::string id_line(const std::string& names) {
  constexpr char kHex[] = "0123456789abcdef";
  std::string line;
  for (const char c : names) {
    const auto byte = static_cast<unsigned char>(c);
    std::string shown(1, c);
    if (byte < 0x20 || byte == 0x7f) shown = {'\\', 'x', kHex[byte >> 4], kHex[byte & 0xf]};
    if (line.size() + shown.size() > 80) break;
    line += shown;
  }
  return line;
}

int uff_channel_position(std::vector<std::string>& names, const std::string& name) {
  const auto at = std::find(names.begin(), names.end(), name);
  if (at != names.end()) return static_cast<int>(at - names.begin());
  names.push_back(name);
  return static_cast<int>(names.size()) - 1;
}

}  // namespace

MimoFrf parse_uff58(std::string_view text, const std::string& source) {
  std::vector<std::string> lines;
  {
    std::size_t at = 0;
    while (at <= text.size()) {
      std::size_t end = text.find('\n', at);
      if (end == std::string_view::npos) end = text.size();
      std::string line(text.substr(at, end - at));
      if (!line.empty() && line.back() == '\r') line.pop_back();
      lines.push_back(std::move(line));
      at = end + 1;
    }
  }
  std::vector<Record> records;
  std::size_t q = 0;
  while (q < lines.size()) {
    if (!is_delimiter(lines[q])) {
      require(trim(lines[q]).empty(), source, ":", q + 1, ": '", internal::echo(trim(lines[q])),
              "' is outside any dataset (a dataset opens with a line holding -1)");
      ++q;
      continue;
    }
    require(q + 1 < lines.size(), source, ":", q + 1, ": a dataset opens but the file ends");
    const std::vector<std::string> head = tokens(lines[q + 1]);
    require(!head.empty(), source, ":", q + 2, ": the dataset number is missing");
    std::size_t end = q + 2;
    while (end < lines.size() && !is_delimiter(lines[end])) ++end;
    require(end < lines.size(), source, ":", q + 1, ": dataset ", internal::echo(head[0]),
            " is not closed by a line holding -1");
    require(head[0] != "58b", source, ":", q + 2,
            ": dataset 58b (binary) is not read; export the FRFs as ASCII dataset 58");
    if (head[0] == "58") {
      const std::vector<std::string> body(lines.begin() + static_cast<std::ptrdiff_t>(q + 2),
                                          lines.begin() + static_cast<std::ptrdiff_t>(end));
      records.push_back(parse_record(body, static_cast<int>(q + 3), source));
    }
    q = end + 1;
  }
  require(!records.empty(), source, ": no dataset 58 (FRF record) in the file");

  MimoFrf frf;
  std::map<std::pair<int, int>, const Record*> by_pair;
  for (const Record& r : records) {
    const int j = uff_channel_position(frf.output_names, r.output);
    const int k = uff_channel_position(frf.input_names, r.input);
    const auto [at, inserted] = by_pair.emplace(std::make_pair(j, k), &r);
    require(inserted, source, ": dataset 58 at line ", r.line, " repeats response ", r.output,
            " / reference ", r.input, " (first at line ", at->second->line, ")");
    const Record& first = records.front();
    bool same = r.frequencies.size() == first.frequencies.size();
    for (Eigen::Index l = 0; same && l < r.frequencies.size(); ++l) {
      same = std::abs(r.frequencies(l) - first.frequencies(l)) <=
             1e-6 * std::max(std::abs(first.frequencies(l)), 1e-300);
    }
    require(same, source, ": dataset 58 at line ", r.line, " (", r.output, " / ", r.input,
            ") has another abscissa than the one at line ", first.line,
            "; every record of the FRF matrix must share its frequencies");
  }
  const int n_y = frf.output_count();
  const int n_u = frf.input_count();
  for (int j = 0; j < n_y; ++j) {
    for (int k = 0; k < n_u; ++k) {
      require(by_pair.count({j, k}) == 1, source, ": the FRF from reference ",
              frf.input_names[static_cast<size_t>(k)], " to response ",
              frf.output_names[static_cast<size_t>(j)], " is missing; the records must hold all ",
              n_y, " x ", n_u, " response/reference pairs");
    }
  }
  frf.frequencies = records.front().frequencies;
  const Eigen::Index lines_count = frf.frequencies.size();
  for (Eigen::Index l = 0; l < lines_count; ++l) {
    require(frf.frequencies(l) >= 0.0 && (l == 0 || frf.frequencies(l) > frf.frequencies(l - 1)),
            source, ": the abscissa of dataset 58 at line ", records.front().line,
            " is not increasing and non-negative at value ", l + 1);
  }
  frf.response.assign(static_cast<size_t>(lines_count), Eigen::MatrixXcd(n_y, n_u));
  for (const auto& [pair, record] : by_pair) {
    for (Eigen::Index l = 0; l < lines_count; ++l) {
      frf.response[static_cast<size_t>(l)](pair.first, pair.second) = record->values(l);
    }
  }
  return frf;
}

MimoFrf read_uff58(const std::filesystem::path& path) {
  return parse_uff58(read_text_file(path), path.string());
}

std::string format_uff58(const MimoFrf& frf) {
  const Eigen::Index n = frf.frequencies.size();
  require(static_cast<Eigen::Index>(frf.response.size()) == n,
          "format_uff58: ", frf.response.size(), " response matrices for ", n, " frequencies");
  const std::vector<Channel> responses = channels_of(frf.output_names, 1);
  const std::vector<Channel> references = channels_of(frf.input_names, 1001);
  std::string out;
  char buffer[160];
  int id = 0;
  for (int j = 0; j < frf.output_count(); ++j) {
    for (int k = 0; k < frf.input_count(); ++k) {
      const Channel& response = responses[static_cast<size_t>(j)];
      const Channel& reference = references[static_cast<size_t>(k)];
      out += "    -1\n    58\n";
      out += id_line(frf.output_names[static_cast<size_t>(j)] + "/" +
                     frf.input_names[static_cast<size_t>(k)]) +
             "\nNONE\nNONE\nNONE\nNONE\n";
      std::snprintf(buffer, sizeof buffer, "%5d%10d%5d%10d %-10s%10ld%4ld %-10s%10ld%4ld\n", 4,
                    ++id, 1, 0, "NONE", response.node, response.direction, "NONE", reference.node,
                    reference.direction);
      out += buffer;
      std::snprintf(buffer, sizeof buffer, "%10d%10ld%10d", 6, static_cast<long>(n), 0);
      out += buffer;
      out += format_e(0.0, 13, 5) + format_e(0.0, 13, 5) + format_e(0.0, 13, 5) + "\n";
      out += "        18    0    0    0 Frequency            Hz                  \n";
      out += "         0    0    0    0 NONE                 NONE                \n";
      out += "         0    0    0    0 NONE                 NONE                \n";
      out += "         0    0    0    0 NONE                 NONE                \n";
      for (Eigen::Index l = 0; l < n; ++l) {
        const std::complex<double> h = frf.response[static_cast<size_t>(l)](j, k);
        out += format_e(frf.frequencies(l) / (2.0 * std::numbers::pi), 13, 5);
        for (const double part : {h.real(), h.imag()}) {
          // 12 decimals fill the 20-character field when the exponent has three digits
          // (|x| < 1e-99 or >= 1e100): one decimal fewer keeps the blank that separates the
          // value from the one before it (the reader splits on blanks).
          std::string field = format_e(part, 20, 12);
          if (field[0] != ' ') field = format_e(part, 20, 11);
          out += field;
        }
        out += "\n";
      }
      out += "    -1\n";
    }
  }
  return out;
}

void write_uff58(const std::filesystem::path& path, const MimoFrf& frf, Overwrite overwrite) {
  write_text_file(path, format_uff58(frf), overwrite);
}

}  // namespace ctid::io

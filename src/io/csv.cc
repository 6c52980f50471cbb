#include "ctid/io/csv.h"

#include <locale.h>  // newlocale, strtod_l
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <string>
#include <system_error>

#include "ctid/core/error.h"
#include "io/internal/echo.h"

namespace ctid::io {

using internal::echo;
namespace {

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

// A field without the double quotes around it ("uEst" -> uEst; a "" inside stays as it is).
std::string_view unquote(std::string_view field) {
  if (field.size() >= 2 && field.front() == '"' && field.back() == '"') {
    return trim(field.substr(1, field.size() - 2));
  }
  return field;
}

// The fields of a line split at `delimiter` outside double quotes, trimmed and unquoted.
std::vector<std::string_view> split_fields(std::string_view line, char delimiter) {
  std::vector<std::string_view> fields;
  size_t begin = 0;
  bool quoted = false;
  for (size_t i = 0; i <= line.size(); ++i) {
    if (i < line.size() && line[i] == '"') quoted = !quoted;
    if (i == line.size() || (line[i] == delimiter && !quoted)) {
      fields.push_back(unquote(trim(line.substr(begin, i - begin))));
      begin = i + 1;
    }
  }
  return fields;
}

// The delimiter of a header row: the one of ',', ';' and tab it holds most often outside
// quotes (',' on a tie, and for a one-column file).
char detect_delimiter(std::string_view header) {
  size_t commas = 0, semicolons = 0, tabs = 0;
  bool quoted = false;
  for (const char c : header) {
    if (c == '"') quoted = !quoted;
    if (quoted) continue;
    commas += c == ',';
    semicolons += c == ';';
    tabs += c == '\t';
  }
  if (semicolons > commas && semicolons >= tabs) return ';';
  if (tabs > commas && tabs > semicolons) return '\t';
  return ',';
}

// The whole field as a double, or nullopt if it is not exactly one number. A leading '+'
// is accepted (std::from_chars does not).
std::optional<double> parse_number(std::string_view field) {
  std::string_view digits = field;
  if (!digits.empty() && digits.front() == '+') {
    digits.remove_prefix(1);
    if (!digits.empty() && (digits.front() == '+' || digits.front() == '-')) return std::nullopt;
  }
  if (digits.empty()) return std::nullopt;
  double value = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (end != digits.data() + digits.size()) return std::nullopt;
  if (ec == std::errc::result_out_of_range) {
    // Overflow (1e999) or underflow (1e-999): strtod gives the IEEE result, +-inf or a
    // denormal / signed zero, and the caller rejects the infinite case.
    // strtod_l in the C locale: strtod follows LC_NUMERIC, which Python may have set to a
    // comma locale, and would stop at the '.' of 1.5e999.
    static const locale_t c_locale = ::newlocale(LC_ALL_MASK, "C", static_cast<locale_t>(0));
    const std::string copy(digits);
    return ::strtod_l(copy.c_str(), nullptr, c_locale);
  }
  if (ec != std::errc()) return std::nullopt;
  return value;
}

// Why a field may not be a number in this file's dialect, for the message ("" when no
// reason is seen): a decimal comma in a comma-separated file, or a delimiter the header did
// not use.
std::string dialect_hint(std::string_view field, char delimiter) {
  if (delimiter == ',' &&
      (field.find(';') != std::string_view::npos || field.find('\t') != std::string_view::npos)) {
    return "; the file looks separated by semicolons or tabs, but its header row has more "
           "commas";
  }
  return "";
}

bool valid_name(std::string_view name) {
  return !name.empty() && name.find_first_of(",\n\r") == std::string_view::npos &&
         trim(name) == name;
}

// What format_csv can write so that it reads back: no quote or line break, no surrounding
// blanks (a name with a delimiter is written quoted).
bool writable_name(std::string_view name) {
  return !name.empty() && name.find_first_of("\"\n\r") == std::string_view::npos &&
         trim(name) == name;
}

std::string join_names(const std::vector<std::string>& names) {
  std::string joined;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) joined += ", ";
    joined += echo(names[i]);
  }
  return joined;
}

}  // namespace

bool CsvTable::has_column(std::string_view name) const {
  for (const auto& n : names) {
    if (n == name) return true;
  }
  return false;
}

const Eigen::VectorXd& CsvTable::column(std::string_view name) const {
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] != name) continue;
    if (const auto bad = unreadable.find(name); bad != unreadable.end()) {
      throw InvalidArgument(bad->second);
    }
    return columns[i];
  }
  throw InvalidArgument(ctid::internal::concat(source, ": no column '", echo(name),
                                               "' (columns: ", join_names(names), ")"));
}

void CsvTable::add_column(std::string name, Eigen::VectorXd values) {
  require(valid_name(name), "CSV column name '", name,
          "' is invalid: it must be non-empty, without commas, line breaks or surrounding "
          "spaces");
  require(!has_column(name), "CSV column '", name, "' is already present");
  require(columns.empty() || values.size() == columns.front().size(), "CSV column '", name,
          "' has ", values.size(), " values but the other columns have ",
          columns.empty() ? 0 : columns.front().size());
  names.push_back(std::move(name));
  columns.push_back(std::move(values));
}

namespace {

// "key: value" with key made of letters, digits and '_'; anything else is a plain comment.
std::optional<CsvDeclaration> parse_declaration(std::string_view comment) {
  comment = trim(comment);
  const size_t colon = comment.find(':');
  if (colon == std::string_view::npos || colon == 0) return std::nullopt;
  const std::string_view key = comment.substr(0, colon);
  for (const char c : key) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return std::nullopt;
  }
  return CsvDeclaration{std::string(key), std::string(trim(comment.substr(colon + 1))), 0};
}

}  // namespace

const CsvDeclaration* CsvTable::declaration(std::string_view key) const {
  const CsvDeclaration* found = nullptr;
  for (const CsvDeclaration& d : declarations) {
    if (d.key == key) found = &d;
  }
  return found;
}

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t'; }
bool is_line_end(char c) { return c == '\n' || c == '\r'; }

// One data row on the fast path: `fields` numbers separated by commas, each with optional
// blanks around it, from `p` to the end of the line. Appends the values to `values` and
// returns the end of the line, or returns nullptr (and appends nothing) for anything else;
// the caller then reads the line again the slow way, which builds the message. It accepts
// a subset of what the slow path accepts and gives the same values, so no string is built
// for a well-formed row.
const char* parse_row_fast(const char* p, const char* end, size_t fields, char delimiter,
                           std::vector<double>& values) {
  const size_t first = values.size();
  for (size_t i = 0; i < fields; ++i) {
    while (p < end && is_blank(*p)) ++p;
    if (p < end && *p == '+') {
      ++p;
      if (p < end && (*p == '+' || *p == '-')) break;
    }
    double value = 0.0;
    const auto [after, ec] = std::from_chars(p, end, value);
    if (ec != std::errc() || after == p || !std::isfinite(value)) break;
    p = after;
    while (p < end && is_blank(*p)) ++p;
    if (i + 1 < fields) {
      if (p == end || *p != delimiter) break;
      ++p;
      values.push_back(value);
      continue;
    }
    if (p != end && *p == delimiter) {  // a delimiter that ends every line (spreadsheets)
      ++p;
      while (p < end && is_blank(*p)) ++p;
    }
    if (p != end && !is_line_end(*p)) break;
    values.push_back(value);
    return p;
  }
  values.resize(first);
  return nullptr;
}

// parse_csv's header row: every name present, unquoted inside, given once, and not all of
// them numbers (a file without a header).
void check_csv_header(const std::vector<std::string_view>& fields, const std::string& source,
                      int line_number) {
  bool all_numbers = true;
  for (size_t i = 0; i < fields.size(); ++i) {
    const std::string_view name = fields[i];
    require(!name.empty(), source, ":", line_number, ": header field ", i + 1,
            " is empty; every column needs a name");
    require(name.find('"') == std::string_view::npos, source, ":", line_number, ": column name '",
            echo(name), "' holds a double quote; quote a name whole (\"name\") or not at all");
    for (size_t j = 0; j < i; ++j) {
      require(fields[j] != name, source, ":", line_number, ": column name '", echo(name),
              "' appears twice in the header");
    }
    all_numbers = all_numbers && parse_number(name).has_value();
  }
  require(!all_numbers, source, ":", line_number,
          ": the first line holds numbers, not column names; a CSV file must start with "
          "a header row such as 't,u,y'");
}

// parse_csv's slow path for one data row of `fields` (as many as the header's): each value
// appended to `values`, a cell that is not a finite number as NaN with its column's problem.
void parse_csv_row_slowly(const std::vector<std::string_view>& fields, char delimiter,
                          const std::string& source, int line_number, CsvTable& table,
                          std::vector<double>& values) {
  for (size_t i = 0; i < fields.size(); ++i) {
    // A cell that is not a finite number is an error of its column, thrown only if the
    // column is used (CsvTable::column): exports carry notes and empty columns.
    const auto problem = [&](const std::string& what) {
      table.unreadable.try_emplace(
          table.names[i],
          ctid::internal::concat(source, ":", line_number, ": column '", echo(table.names[i]),
                                 "' (field ", i + 1, "): ", what));
      values.push_back(std::numeric_limits<double>::quiet_NaN());
    };
    if (fields[i].empty()) {
      problem("empty field; expected a number");
      continue;
    }
    std::optional<double> value = parse_number(fields[i]);
    if (!value && delimiter != ',' && fields[i].find(',') != std::string_view::npos) {
      // A decimal comma, as spreadsheets in many locales write beside ';' or tabs.
      std::string with_point(fields[i]);
      std::replace(with_point.begin(), with_point.end(), ',', '.');
      value = parse_number(with_point);
    }
    if (!value) {
      problem("malformed number '" + echo(fields[i]) + "'" + dialect_hint(fields[i], delimiter));
    } else if (!std::isfinite(*value)) {
      problem("value '" + echo(fields[i]) + "' is not finite; every value must be a finite number");
    } else {
      values.push_back(*value);
    }
  }
}

}  // namespace

CsvTable parse_csv(std::string_view text, const std::string& source) {
  CsvTable table;
  table.source = source;
  // The data rows, row after row (row-major), moved into columns at the end.
  std::vector<double> values;
  size_t width = 0;
  char delimiter = ',';
  int header_line = 0;
  int line_number = 0;
  const char* const text_end = text.data() + text.size();
  // A UTF-8 byte order mark (spreadsheets write one) is not part of the first column name.
  size_t position = text.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
  while (position < text.size()) {
    ++line_number;
    // The fast path for a data row: no line is cut out and no message is prepared.
    if (header_line != 0) {
      const char* p = text.data() + position;
      while (p < text_end && is_blank(*p)) ++p;
      if (p < text_end && !is_line_end(*p) && *p != '#') {
        if (const char* line_end = parse_row_fast(p, text_end, width, delimiter, values)) {
          position = static_cast<size_t>(line_end - text.data()) + 1;
          if (line_end < text_end && *line_end == '\r' && position < text.size() &&
              text[position] == '\n') {
            ++position;
          }
          continue;
        }
      }
    }
    // Lines end with LF, CRLF or a lone CR (old Mac files).
    size_t end = text.find_first_of("\r\n", position);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = trim(text.substr(position, end - position));
    // A byte order mark before the header row after comment lines (files joined by tools) is
    // not part of the first name either.
    if (header_line == 0 && line.substr(0, 3) == "\xEF\xBB\xBF") line = trim(line.substr(3));
    position = end + 1;
    if (end < text.size() && text[end] == '\r' && position < text.size() &&
        text[position] == '\n') {
      ++position;
    }
    if (line.empty()) continue;
    if (line.front() == '#') {
      if (auto declaration = parse_declaration(line.substr(1))) {
        declaration->line = line_number;
        table.declarations.push_back(std::move(*declaration));
      }
      continue;
    }

    if (header_line == 0) delimiter = detect_delimiter(line);
    auto fields = split_fields(line, delimiter);
    // A delimiter that ends every line leaves an empty last field: not a value.
    if (fields.size() > 1 && fields.back().empty() &&
        (header_line == 0 || fields.size() == width + 1)) {
      fields.pop_back();
    }
    if (header_line == 0) {
      header_line = line_number;
      check_csv_header(fields, source, line_number);
      for (const auto& name : fields) table.names.emplace_back(name);
      width = fields.size();
      // Room for the rows the rest of the text holds if they are as long as ~20 bytes a value.
      values.reserve((text.size() - std::min(position, text.size())) / 20 + width);
      continue;
    }

    // The slow path: a row the fast path did not take (an error, or a value such as 1e999
    // that needs strtod). Messages are built here only.
    require(fields.size() == width, source, ":", line_number, ": expected ", width, " fields (",
            join_names(table.names), ") but found ", fields.size());
    parse_csv_row_slowly(fields, delimiter, source, line_number, table, values);
  }
  require(header_line != 0, source,
          ": file is empty; expected a header row of column names such as 't,u,y'");
  const size_t rows = values.size() / width;
  require(rows > 0, source, ": no data rows after the header on line ", header_line);
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
      matrix(values.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(width));
  table.columns.reserve(width);
  for (size_t i = 0; i < width; ++i) {
    table.columns.emplace_back(matrix.col(static_cast<Eigen::Index>(i)));
  }
  return table;
}

CsvTable read_csv(const std::filesystem::path& path) {
  return parse_csv(read_text_file(path), path.string());
}

std::string format_csv(const CsvTable& table) {
  require(!table.names.empty(), "a CSV table needs at least one column");
  require(table.names.size() == table.columns.size(), "CSV table has ", table.names.size(),
          " names but ", table.columns.size(), " columns");
  const Eigen::Index rows = table.columns.front().size();
  for (size_t i = 0; i < table.names.size(); ++i) {
    require(writable_name(table.names[i]), "CSV column name '", table.names[i], "' is invalid");
    require(table.columns[i].size() == rows, "CSV column '", table.names[i], "' has ",
            table.columns[i].size(), " values but column '", table.names[0], "' has ", rows);
  }
  std::string text;
  text.reserve(static_cast<size_t>(rows + 1) * table.names.size() * 25);
  for (const CsvDeclaration& d : table.declarations) text += "# " + d.key + ": " + d.value + "\n";
  for (size_t i = 0; i < table.names.size(); ++i) {
    if (i > 0) text += ',';
    // Quoted when it holds a delimiter or starts like a comment, so it reads back whole.
    const std::string& name = table.names[i];
    const bool quote = name.find_first_of(",;\t") != std::string::npos || name.front() == '#';
    text += quote ? "\"" + name + "\"" : name;
  }
  text += '\n';
  char buffer[32];
  for (Eigen::Index k = 0; k < rows; ++k) {
    for (size_t i = 0; i < table.columns.size(); ++i) {
      if (i > 0) text += ',';
      // to_chars: "%.17g" of the C locale whatever LC_NUMERIC says (a comma locale set in
      // Python made snprintf write 0,05 into the CSV).
      const auto written = std::to_chars(buffer, buffer + sizeof buffer, table.columns[i](k),
                                         std::chars_format::general, 17);
      text.append(buffer, written.ptr);
    }
    text += '\n';
  }
  return text;
}

void write_csv(const std::filesystem::path& path, const CsvTable& table, Overwrite overwrite) {
  write_text_file(path, format_csv(table), overwrite);
}

}  // namespace ctid::io

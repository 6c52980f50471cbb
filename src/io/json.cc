#include "ctid/io/json.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "ctid/core/error.h"

namespace ctid::io {
namespace {

// nlohmann reports the byte offset just past the offending character; the line and column
// are recomputed here so the message has the "file:line:column" form editors jump to.
std::string parse_error_location(std::string_view text, size_t byte) {
  const size_t offending = byte == 0 ? 0 : std::min(byte - 1, text.size());
  int line = 1;
  size_t line_start = 0;
  for (size_t i = 0; i < offending; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  return std::to_string(line) + ":" + std::to_string(offending - line_start + 1);
}

// "[json.exception.parse_error.101] parse error at line 3, column 5: syntax error while
// parsing value - invalid literal; last read: 'NaN'" -> "syntax error while parsing value -
// invalid literal; last read: 'NaN'".
std::string parse_error_reason(const std::string& what) {
  const size_t colon = what.find(": ");
  return colon == std::string::npos ? what : what.substr(colon + 2);
}

std::string kind_of(const nlohmann::json& value) {
  if (value.is_null()) return "null";
  if (value.is_boolean()) return "a boolean";
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_array()) return "an array";
  return "an object";
}

// The deepest nesting of arrays and objects a document may have. nlohmann's parser is
// iterative, but copying, comparing and printing a document recurse once per level, so a
// hostile file (140 000 nested '[') would overflow the stack after parsing; ctid's own
// documents nest fewer than ten levels.
constexpr int kMaxNestingDepth = 256;

// The byte offset of the first bracket that opens level kMaxNestingDepth + 1, or npos.
// Brackets inside strings (with their escapes) do not count.
size_t too_deep_at(std::string_view text) {
  int depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxNestingDepth) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return std::string_view::npos;
}

}  // namespace

nlohmann::json parse_json(std::string_view text, const std::string& source) {
  if (const size_t at = too_deep_at(text); at != std::string_view::npos) {
    throw InvalidArgument(source + ":" + parse_error_location(text, at + 1) +
                          ": malformed JSON: arrays and objects nested deeper than " +
                          std::to_string(kMaxNestingDepth) + " levels");
  }
  // A key given twice in one object would silently keep its last value: refused instead.
  struct DuplicateKey {
    std::string key;
  };
  std::vector<std::set<std::string>> keys;  // of each object being parsed, innermost last
  const nlohmann::json::parser_callback_t check_keys =
      [&keys](int /*depth*/, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        using Event = nlohmann::json::parse_event_t;
        if (event == Event::object_start) {
          keys.emplace_back();
        } else if (event == Event::object_end) {
          if (!keys.empty()) keys.pop_back();
        } else if (event == Event::key && !keys.empty()) {
          const std::string& key = parsed.get_ref<const std::string&>();
          if (!keys.back().insert(key).second) throw DuplicateKey{key};
        }
        return true;
      };
  try {
    return nlohmann::json::parse(text.begin(), text.end(), check_keys);
  } catch (const DuplicateKey& d) {
    throw InvalidArgument(source + ": malformed JSON: the key \"" + d.key +
                          "\" appears twice in one object");
  } catch (const nlohmann::json::parse_error& e) {
    throw InvalidArgument(source + ":" + parse_error_location(text, e.byte) +
                          ": malformed JSON: " + parse_error_reason(e.what()));
  } catch (const nlohmann::json::out_of_range& e) {
    // A number too large for a double ("number overflow parsing '1e999'") carries no
    // position; the first occurrence of the quoted literal locates it.
    const std::string what = e.what();
    const size_t open = what.find('\'');
    const size_t close = open == std::string::npos ? open : what.find('\'', open + 1);
    std::string location = "1:1";
    if (close != std::string::npos) {
      const size_t at = text.find(what.substr(open + 1, close - open - 1));
      if (at != std::string_view::npos) location = parse_error_location(text, at + 1);
    }
    const size_t bracket = what.find("] ");
    throw InvalidArgument(source + ":" + location + ": malformed JSON: " +
                          (bracket == std::string::npos ? what : what.substr(bracket + 2)) +
                          " (out of the range of a double)");
  }
}

nlohmann::json read_json(const std::filesystem::path& path) {
  // Parsing takes about ten times a document's size in memory: a model file of 26 million
  // coefficients took 1.8 GB before it was refused. ctid's documents are far smaller.
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  require(ec || size <= kMaxJsonDocumentBytes, path.string(), ": ", size >> 20,
          " MiB; ctid reads JSON documents (models, controllers, specs, results) of at most ",
          kMaxJsonDocumentBytes >> 20, " MiB");
  std::string text = read_text_file(path);
  require(text.size() <= kMaxJsonDocumentBytes, path.string(), ": more than ",
          kMaxJsonDocumentBytes >> 20,
          " MiB; ctid reads JSON documents (models, controllers, specs, results) of at most that");
  return parse_json(text, path.string());
}

namespace {

// The length of the well-formed UTF-8 sequence at text[at] (RFC 3629: no overlong forms, no
// surrogates, nothing above U+10FFFF), or 0 when the byte there does not start one.
std::size_t utf8_sequence_length(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[at + k]); };
  const unsigned char lead = byte(0);
  if (lead < 0x80) return 1;
  std::size_t length = 0;
  unsigned char low = 0x80;  // the range of the second byte
  unsigned char high = 0xbf;
  if (lead >= 0xc2 && lead <= 0xdf) {
    length = 2;
  } else if (lead >= 0xe0 && lead <= 0xef) {
    length = 3;
    if (lead == 0xe0) low = 0xa0;   // overlong
    if (lead == 0xed) high = 0x9f;  // surrogates
  } else if (lead >= 0xf0 && lead <= 0xf4) {
    length = 4;
    if (lead == 0xf0) low = 0x90;   // overlong
    if (lead == 0xf4) high = 0x8f;  // above U+10FFFF
  } else {
    return 0;
  }
  if (at + length > text.size()) return 0;
  if (byte(1) < low || byte(1) > high) return 0;
  for (std::size_t k = 2; k < length; ++k) {
    if (byte(k) < 0x80 || byte(k) > 0xbf) return 0;
  }
  return length;
}

bool is_utf8(std::string_view text) {
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t length = utf8_sequence_length(text, at);
    if (length == 0) return false;
    at += length;
  }
  return true;
}

// A copy of `value` whose strings and keys are escape_invalid_utf8's.
nlohmann::json with_utf8_strings(const nlohmann::json& value) {
  if (value.is_string()) return escape_invalid_utf8(value.get_ref<const std::string&>());
  if (value.is_array()) {
    nlohmann::json out = nlohmann::json::array();
    for (const nlohmann::json& item : value) out.push_back(with_utf8_strings(item));
    return out;
  }
  if (value.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (const auto& [key, item] : value.items()) {
      out[escape_invalid_utf8(key)] = with_utf8_strings(item);
    }
    return out;
  }
  return value;
}

}  // namespace

std::string escape_invalid_utf8(std::string_view text) {
  if (is_utf8(text)) return std::string(text);
  constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size() + 16);
  for (std::size_t at = 0; at < text.size();) {
    const std::size_t length = utf8_sequence_length(text, at);
    if (length == 0) {
      const auto c = static_cast<unsigned char>(text[at]);
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xf];
      ++at;
    } else {
      out.append(text, at, length);
      at += length;
    }
  }
  return out;
}

std::string json_text(const nlohmann::json& value, int indent) {
  try {
    return value.dump(indent);
  } catch (const nlohmann::json::type_error& e) {
    if (e.id != 316) throw;  // 316: a string that is not UTF-8
  }
  return with_utf8_strings(value).dump(indent);
}

void write_json(const std::filesystem::path& path, const nlohmann::json& value,
                Overwrite overwrite) {
  write_text_file(path, json_text(value) + "\n", overwrite);
}

namespace {

// The type is checked before JsonObject copies the value, so a document that is not an
// object (a huge array, say) is refused without being copied.
const nlohmann::json& require_object(const nlohmann::json& value, const std::string& source,
                                     const std::string& path) {
  if (!value.is_object()) {
    throw InvalidArgument(ctid::internal::concat(source, ": ", path.empty() ? "document" : path,
                                                 ": expected a JSON object but found ",
                                                 kind_of(value)));
  }
  return value;
}

}  // namespace

JsonObject::JsonObject(const nlohmann::json& value, std::string source, std::string path)
    : value_(require_object(value, source, path)),
      source_(std::move(source)),
      path_(std::move(path)) {}

std::string JsonObject::field_path(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

void JsonObject::fail(std::string_view key, std::string_view message) const {
  // A JSON string may hold "\u0000": a NUL byte in the message would end what() there
  // (the message was cut mid-word), so it is written \x00 as the frame writes other control
  // bytes.
  std::string text = ctid::internal::concat(source_, ": ", field_path(key), ": ", message);
  for (size_t at = text.find('\0'); at != std::string::npos; at = text.find('\0', at)) {
    text.replace(at, 1, "\\x00");
  }
  throw InvalidArgument(text);
}

bool JsonObject::has(std::string_view key) const {
  known_.emplace(key);
  return value_.contains(key);
}

const nlohmann::json& JsonObject::field(std::string_view key) const {
  known_.emplace(key);
  const auto it = value_.find(key);
  if (it == value_.end()) fail(key, "required field is missing");
  return *it;
}

double JsonObject::number(std::string_view key) const {
  const nlohmann::json& v = field(key);
  if (!v.is_number()) fail(key, "expected a number but found " + kind_of(v));
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail(key, "value is not finite");
  return x;
}

double JsonObject::number_or(std::string_view key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

long long JsonObject::integer(std::string_view key) const {
  const nlohmann::json& v = field(key);
  if (v.is_number_integer()) return v.get<long long>();
  if (v.is_number_float()) {
    const double x = v.get<double>();
    if (std::isfinite(x) && std::floor(x) == x && std::abs(x) < 9.0e15) {
      return static_cast<long long>(x);
    }
  }
  fail(key, "expected an integer but found " + (v.is_number() ? v.dump() : kind_of(v)));
}

long long JsonObject::integer_or(std::string_view key, long long fallback) const {
  return has(key) ? integer(key) : fallback;
}

std::string JsonObject::string(std::string_view key) const {
  const nlohmann::json& v = field(key);
  if (!v.is_string()) fail(key, "expected a string but found " + kind_of(v));
  return v.get<std::string>();
}

std::string JsonObject::string_or(std::string_view key, std::string fallback) const {
  return has(key) ? string(key) : std::move(fallback);
}

bool JsonObject::boolean_or(std::string_view key, bool fallback) const {
  if (!has(key)) return fallback;
  const nlohmann::json& v = field(key);
  if (!v.is_boolean()) fail(key, "expected true or false but found " + kind_of(v));
  return v.get<bool>();
}

Eigen::VectorXd JsonObject::numbers(std::string_view key, bool allow_empty) const {
  const nlohmann::json& v = field(key);
  if (!v.is_array()) fail(key, "expected an array of numbers but found " + kind_of(v));
  if (v.empty() && !allow_empty) fail(key, "the array is empty; at least one number is needed");
  Eigen::VectorXd out(static_cast<Eigen::Index>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) {
    const std::string entry = std::string(key) + "[" + std::to_string(i) + "]";
    if (!v[i].is_number()) fail(entry, "expected a number but found " + kind_of(v[i]));
    const double x = v[i].get<double>();
    if (!std::isfinite(x)) fail(entry, "value is not finite");
    out(static_cast<Eigen::Index>(i)) = x;
  }
  return out;
}

std::vector<Eigen::VectorXd> JsonObject::number_rows(std::string_view key) const {
  const nlohmann::json& v = field(key);
  if (!v.is_array()) fail(key, "expected an array of arrays of numbers but found " + kind_of(v));
  if (v.empty()) fail(key, "the array is empty; at least one row is needed");
  std::vector<Eigen::VectorXd> rows;
  for (size_t i = 0; i < v.size(); ++i) {
    const std::string entry = std::string(key) + "[" + std::to_string(i) + "]";
    if (!v[i].is_array()) fail(entry, "expected an array of numbers but found " + kind_of(v[i]));
    if (v[i].empty()) fail(entry, "the array is empty; at least one number is needed");
    Eigen::VectorXd row(static_cast<Eigen::Index>(v[i].size()));
    for (size_t c = 0; c < v[i].size(); ++c) {
      const std::string at = entry + "[" + std::to_string(c) + "]";
      if (!v[i][c].is_number()) fail(at, "expected a number but found " + kind_of(v[i][c]));
      row(static_cast<Eigen::Index>(c)) = v[i][c].get<double>();
      if (!std::isfinite(row(static_cast<Eigen::Index>(c)))) fail(at, "value is not finite");
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

JsonObject JsonObject::object(std::string_view key) const {
  return JsonObject(field(key), source_, field_path(key));
}

std::vector<JsonObject> JsonObject::objects(std::string_view key) const {
  const nlohmann::json& v = field(key);
  if (!v.is_array()) fail(key, "expected an array of objects but found " + kind_of(v));
  if (v.empty()) fail(key, "the array is empty; at least one entry is needed");
  std::vector<JsonObject> out;
  out.reserve(v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    out.emplace_back(v[i], source_, field_path(key) + "[" + std::to_string(i) + "]");
  }
  return out;
}

void JsonObject::finish() const {
  for (const auto& item : value_.items()) {
    if (known_.find(item.key()) == known_.end()) {
      std::string known;
      for (const auto& k : known_) known += (known.empty() ? "" : ", ") + k;
      fail(item.key(), "unknown field (known fields here: " + known + ")");
    }
  }
}

}  // namespace ctid::io

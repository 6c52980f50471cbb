// JSON documents for the io layer (nlohmann::json). Syntax errors name the source, line and
// column ("model.json:4:17: malformed JSON: ..."); JsonObject reads fields strictly, with
// messages that name the source and the field's path ("model.json: submodels[1].
// numerator_ascending: expected an array of numbers"), and rejects unknown fields.
#pragma once

#include <filesystem>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ctid/io/file.h"

namespace ctid::io {

/// The largest JSON document read_json reads (64 MiB): parsing costs about ten times a
/// document's size in memory, and ctid's documents are far smaller.
inline constexpr std::size_t kMaxJsonDocumentBytes = std::size_t{64} << 20;

/// Parses JSON text; `source` names it in error messages (InvalidArgument).
nlohmann::json parse_json(std::string_view text, const std::string& source);
/// Reads and parses a JSON file of at most kMaxJsonDocumentBytes (InvalidArgument beyond).
nlohmann::json read_json(const std::filesystem::path& path);
/// `text` with every byte that is not part of well-formed UTF-8 written as the four
/// characters \xHH (lowercase hex, as Python's "backslashreplace" writes them), so that a file
/// name of any bytes can be shown in a message or stored in a JSON document (decision 0042).
/// Text that is UTF-8 is returned unchanged.
std::string escape_invalid_utf8(std::string_view text);
/// `value` as JSON text, `indent` spaces per level (-1: one line): every string and key that
/// is not UTF-8 is written as escape_invalid_utf8 writes it, where nlohmann::json's dump would
/// throw. Every document ctid writes goes through here.
std::string json_text(const nlohmann::json& value, int indent = 2);
/// Writes json_text(value) with a final newline; doubles keep full precision (they read back
/// bit-identical).
void write_json(const std::filesystem::path& path, const nlohmann::json& value,
                Overwrite overwrite = Overwrite::no);

/// A JSON object read field by field. Every accessor marks its key as known;
/// finish() then rejects keys that no accessor asked for, so a misspelt field is an error
/// rather than silently ignored. Errors are InvalidArgument "<source>: <path>: <what>".
class JsonObject {
 public:
  /// Throws unless `value` is an object (kept as a copy, so temporaries are fine). `path`
  /// is the object's location ("" for the root).
  JsonObject(const nlohmann::json& value, std::string source, std::string path = "");

  const std::string& source() const { return source_; }
  const std::string& path() const { return path_; }
  /// The path of a field of this object, e.g. "submodels[1].integrators".
  std::string field_path(std::string_view key) const;

  bool has(std::string_view key) const;
  /// A required finite number.
  double number(std::string_view key) const;
  double number_or(std::string_view key, double fallback) const;
  /// A required integer (a JSON number without fractional part).
  long long integer(std::string_view key) const;
  long long integer_or(std::string_view key, long long fallback) const;
  std::string string(std::string_view key) const;
  std::string string_or(std::string_view key, std::string fallback) const;
  bool boolean_or(std::string_view key, bool fallback) const;
  /// A required array of finite numbers (may be empty only if allow_empty).
  Eigen::VectorXd numbers(std::string_view key, bool allow_empty = false) const;
  /// A required non-empty array of non-empty arrays of finite numbers (rows may differ in
  /// length).
  std::vector<Eigen::VectorXd> number_rows(std::string_view key) const;
  JsonObject object(std::string_view key) const;
  /// A required non-empty array of objects.
  std::vector<JsonObject> objects(std::string_view key) const;

  /// Throws naming the first field that no accessor asked for, and listing the known ones.
  void finish() const;
  /// Throws InvalidArgument "<source>: <path of key>: <message>".
  [[noreturn]] void fail(std::string_view key, std::string_view message) const;

 private:
  const nlohmann::json& field(std::string_view key) const;

  nlohmann::json value_;
  std::string source_;
  std::string path_;
  mutable std::set<std::string, std::less<>> known_;
};

}  // namespace ctid::io

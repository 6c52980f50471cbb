// Batch manifests: the records `ctid batch` runs `ctid fit` on (docs/batch.md), as JSON
// {"spec": {FLAGS}, "records": [{"name": N, "data": FILE or [FILES], FLAGS}]} or as a CSV table
// with a header name,data,FLAGS... (quoted cells, "" inside quotes, CRLF). This reader checks
// the manifest's shape only; what a flag means is the command line's, which passes a check of
// the flag names (`ManifestKeyCheck`) and turns the settings into ctid fit's words.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace ctid::io {

/// A setting as written: a JSON value in a JSON manifest or spec, a string in a CSV cell.
struct ManifestValue {
  nlohmann::json value;
  bool from_csv = false;
};
/// Flag name (without dashes) -> value.
using ManifestSettings = std::map<std::string, ManifestValue>;

/// One record of a manifest.
struct ManifestRecord {
  std::string name;               ///< empty: none given (the command line derives one)
  std::vector<std::string> data;  ///< at least one path; relative ones joined to the manifest's
                                  ///< folder, normalised, and never starting with '-'
  ManifestSettings settings;      ///< the record's own flags
  std::string context;            ///< where it is, for messages: "m.json: record 3 ('a')"
};

struct BatchManifest {
  ManifestSettings spec;  ///< a JSON manifest's "spec" (a CSV manifest has none)
  std::vector<ManifestRecord> records;
};

/// Called with every flag name of a spec, a record or a CSV header and where it is; throws
/// InvalidArgument for a name that is not a flag. An empty check accepts every name.
using ManifestKeyCheck = std::function<void(const std::string& key, const std::string& context)>;

/// "m.json: record 3 ('a')" for the record at `index` (0-based); `source` alone for index < 0.
std::string manifest_context(const std::string& source, int index, const std::string& name);

/// The settings of a spec object (a JSON manifest's "spec" or a --spec file): "name" and "data"
/// belong to records and are refused. Throws InvalidArgument naming the key.
ManifestSettings manifest_settings_from_json(const nlohmann::json& object,
                                             const std::string& context,
                                             const ManifestKeyCheck& check_key = {});

/// A JSON manifest document read from `file` (which names it in messages and whose folder the
/// relative data paths are taken from). Throws InvalidArgument naming what is wrong.
BatchManifest batch_manifest_from_json(const nlohmann::json& document, const std::string& file,
                                       const ManifestKeyCheck& check_key = {});

/// A CSV manifest's text. Throws InvalidArgument naming the line, record or column.
BatchManifest batch_manifest_from_csv(std::string_view text, const std::string& file,
                                      const ManifestKeyCheck& check_key = {});

/// Reads `file`: CSV when its extension is .csv, JSON otherwise.
BatchManifest read_batch_manifest(const std::filesystem::path& file,
                                  const ManifestKeyCheck& check_key = {});

/// Refuses (InvalidArgument naming `context`) a record name that is not a file name on every
/// system: 1 to 200 letters, digits, '.', '_' and '-', not starting with '.' or '-', and not
/// one of the batch's own files (summary, timings, a name ending in .error).
void check_record_name(const std::string& name, const std::string& context);

/// Every record's name, in order: its "name", or one derived from its first data path, safe
/// and unique by construction (the file's stem; records sharing a stem are named by their
/// path from the folder they share, "siteA_rec"; bytes outside [A-Za-z0-9._-] become '_';
/// what still collides is numbered "-2", "-3", ...). Throws InvalidArgument for a given name
/// that check_record_name refuses or that two records give.
std::vector<std::string> record_names(const std::vector<ManifestRecord>& records);

}  // namespace ctid::io

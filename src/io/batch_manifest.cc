#include "ctid/io/batch_manifest.h"

#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <utility>

#include "ctid/core/error.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"

namespace ctid::io {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

// A value shown in a message: compact JSON, bytes that are not UTF-8 replaced rather than a
// dump that throws.
std::string shown(const json& value) {
  return value.dump(-1, ' ', false, json::error_handler_t::replace);
}

void check(const ManifestKeyCheck& check_key, const std::string& key, const std::string& context) {
  if (check_key) check_key(key, context);
}

// The cells of a CSV manifest, row by row: cells separated by ',', a cell that starts with '"'
// runs to the next lone '"' ("" inside it is one quote, and it may span lines), rows end at
// LF, CR or CRLF; blank lines are skipped.
std::vector<std::vector<std::string>> manifest_rows(std::string_view text,
                                                    const std::string& file) {
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string cell;
  bool quoted = false;
  bool any = false;
  int line = 1;
  int quote_line = 1;  // where the open quote is
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        if (c == '\n') ++line;
        cell += c;
      }
      continue;
    }
    if (c == '"' && cell.empty()) {
      quoted = true;
      quote_line = line;
      any = true;
    } else if (c == ',') {
      row.push_back(std::move(cell));
      cell.clear();
      any = true;
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      if (any || !cell.empty()) {
        row.push_back(std::move(cell));
        rows.push_back(std::move(row));
      }
      row.clear();
      cell.clear();
      any = false;
      ++line;
    } else {
      cell += c;
      any = true;
    }
  }
  if (quoted) {
    throw InvalidArgument(file + ": line " + std::to_string(quote_line) +
                          ": the quote opened here is not closed");
  }
  if (any || !cell.empty()) {
    row.push_back(std::move(cell));
    rows.push_back(std::move(row));
  }
  return rows;
}

// "data": a path or a non-empty list of paths, relative ones taken from the manifest's folder;
// a path that would start with '-' gets "./" so that it is never read as a flag.
std::vector<std::string> data_paths(const json& value, const fs::path& base,
                                    const std::string& context) {
  std::vector<std::string> paths;
  const auto add = [&](const json& item) {
    if (!item.is_string() || item.get_ref<const std::string&>().empty()) {
      throw InvalidArgument(context + ": field 'data' is " + shown(item) +
                            "; it is a file path or a list of them");
    }
    fs::path path(item.get<std::string>());
    if (path.is_relative()) path = base / path;
    std::string text = path.lexically_normal().string();
    if (text.empty() || text.front() == '-') text = "./" + text;
    paths.push_back(std::move(text));
  };
  if (value.is_array() && !value.empty()) {
    for (const json& item : value) add(item);
  } else {
    add(value);
  }
  return paths;
}

ManifestSettings settings_of(const json& object, const std::string& context,
                             const ManifestKeyCheck& check_key, bool record) {
  ManifestSettings settings;
  for (const auto& [key, value] : object.items()) {
    if (key == "name" || key == "data") {
      if (record) continue;
      throw InvalidArgument(context + ": field '" + key +
                            "' belongs to a record, not to the shared spec");
    }
    check(check_key, key, context);
    settings[key] = ManifestValue{value, false};
  }
  return settings;
}

// A byte a record name may hold: letters, digits, '.', '_' and '-'.
bool name_byte(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '_' || c == '-';
}

bool batch_file_name(const std::string& name) {
  return name == "summary" || name == "timings" || name.ends_with(".error");
}

// `text` as a record name: every byte check_record_name does not allow becomes '_', a leading
// '.' or '-' gets a '_' before it, the batch's own names get "_record" after them, and the
// result is at most 187 bytes (room for a "-N" that makes it unique).
std::string safe_name(const std::string& text) {
  std::string name;
  for (const char c : text) name += name_byte(c) ? c : '_';
  if (name.empty() || name.front() == '.' || name.front() == '-') name.insert(0, "_");
  if (name.size() > 180) name.resize(180);
  if (batch_file_name(name)) name += "_record";
  return name;
}

// The names of the records without "name" (the others' entries stay empty): the data file's
// stem, or, when several records would share that stem (site_a/rec.csv, site_b/rec.csv), the
// path without extension from the folder all of those records share, '/' written '_'. A name
// still taken gets "-2", "-3", ... so a --glob batch never stops on its names.
std::vector<std::string> derived_names(const std::vector<ManifestRecord>& records) {
  std::map<std::string, std::vector<std::size_t>> by_stem;
  std::set<std::string> taken;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (!records[i].name.empty()) {
      taken.insert(records[i].name);
    } else {
      by_stem[safe_name(fs::path(records[i].data.front()).stem().string())].push_back(i);
    }
  }
  std::vector<std::string> names(records.size());
  for (const auto& [stem, members] : by_stem) {
    if (members.size() == 1 && taken.count(stem) == 0) {
      names[members.front()] = stem;
      continue;
    }
    fs::path shared = fs::path(records[members.front()].data.front()).lexically_normal();
    shared = shared.parent_path();
    for (const std::size_t i : members) {
      const fs::path folder = fs::path(records[i].data.front()).lexically_normal().parent_path();
      while (!shared.empty() && folder.lexically_relative(shared).string().starts_with("..")) {
        const fs::path parent = shared.parent_path();
        if (parent == shared) break;  // a root: nothing above it to share
        shared = parent;
      }
    }
    for (const std::size_t i : members) {
      fs::path relative = fs::path(records[i].data.front()).lexically_normal();
      if (!shared.empty()) relative = relative.lexically_relative(shared);
      relative.replace_extension();
      std::string joined;
      for (const fs::path& part : relative) {
        if (part == "." || part.empty()) continue;
        joined += (joined.empty() ? "" : "_") + part.string();
      }
      names[i] = safe_name(joined.empty() ? stem : joined);
    }
  }
  // What is still shared (a_b.csv beside a/b.csv, a name a record chose) is numbered in order.
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (!records[i].name.empty()) continue;
    std::string name = names[i];
    for (int k = 2; taken.count(name) > 0; ++k) name = names[i] + "-" + std::to_string(k);
    taken.insert(name);
    names[i] = name;
  }
  return names;
}

}  // namespace

std::string manifest_context(const std::string& source, int index, const std::string& name) {
  std::string text = source;
  if (index >= 0) {
    text += ": record " + std::to_string(index + 1);
    if (!name.empty()) text += " ('" + name + "')";
  }
  return text;
}

ManifestSettings manifest_settings_from_json(const json& object, const std::string& context,
                                             const ManifestKeyCheck& check_key) {
  return settings_of(object, context, check_key, false);
}

BatchManifest batch_manifest_from_json(const json& document, const std::string& file,
                                       const ManifestKeyCheck& check_key) {
  if (!document.is_object()) throw InvalidArgument(file + ": a manifest is a JSON object");
  for (const auto& [key, value] : document.items()) {
    if (key != "spec" && key != "records") {
      throw InvalidArgument(file + ": field '" + key + "' is not a manifest field (spec, records)");
    }
  }
  BatchManifest manifest;
  if (const auto spec = document.find("spec"); spec != document.end()) {
    if (!spec->is_object()) throw InvalidArgument(file + ": field 'spec' is a JSON object");
    manifest.spec = settings_of(*spec, file + ": spec", check_key, false);
  }
  const auto records = document.find("records");
  if (records == document.end() || !records->is_array()) {
    throw InvalidArgument(file + ": field 'records' (a list of records) is missing");
  }
  const fs::path base = fs::path(file).parent_path();
  int index = 0;
  for (const json& record : *records) {
    std::string name;
    if (record.is_object() && record.contains("name")) {
      const json& given = record["name"];
      if (!given.is_string()) {
        throw InvalidArgument(manifest_context(file, index, "") + ": field 'name' is " +
                              shown(given) + "; it is a string");
      }
      name = given.get<std::string>();
    }
    const std::string context = manifest_context(file, index, name);
    if (!record.is_object()) throw InvalidArgument(context + ": a record is a JSON object");
    if (!record.contains("data")) throw InvalidArgument(context + ": field 'data' is missing");
    manifest.records.push_back({name, data_paths(record["data"], base, context),
                                settings_of(record, context, check_key, true), context});
    ++index;
  }
  return manifest;
}

BatchManifest batch_manifest_from_csv(std::string_view text, const std::string& file,
                                      const ManifestKeyCheck& check_key) {
  const auto rows = manifest_rows(text, file);
  if (rows.empty()) {
    throw InvalidArgument(file + ": the manifest is empty (expected a header name,data,...)");
  }
  const std::vector<std::string>& header = rows.front();
  std::optional<std::size_t> data_column;
  std::optional<std::size_t> name_column;
  std::set<std::string> seen;
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string& key = header[c];
    if (!seen.insert(key).second) {
      throw InvalidArgument(file + ": column '" + key + "' is given twice");
    }
    if (key == "data") {
      data_column = c;
    } else if (key == "name") {
      name_column = c;
    } else {
      check(check_key, key, file + ": header");
    }
  }
  if (!data_column) throw InvalidArgument(file + ": column 'data' is missing from the header");
  const fs::path base = fs::path(file).parent_path();
  BatchManifest manifest;
  for (std::size_t r = 1; r < rows.size(); ++r) {
    const std::vector<std::string>& row = rows[r];
    const int index = static_cast<int>(r) - 1;
    const std::string name = name_column && *name_column < row.size() ? row[*name_column] : "";
    const std::string context = manifest_context(file, index, name);
    if (row.size() != header.size()) {
      throw InvalidArgument(context + ": " + std::to_string(row.size()) +
                            " cells; the header has " + std::to_string(header.size()));
    }
    if (row[*data_column].empty()) throw InvalidArgument(context + ": field 'data' is missing");
    ManifestRecord record{name, data_paths(json(row[*data_column]), base, context), {}, context};
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (c == *data_column || (name_column && c == *name_column) || row[c].empty()) continue;
      record.settings[header[c]] = ManifestValue{json(row[c]), true};
    }
    manifest.records.push_back(std::move(record));
  }
  return manifest;
}

BatchManifest read_batch_manifest(const fs::path& file, const ManifestKeyCheck& check_key) {
  if (file.extension() == ".csv") {
    return batch_manifest_from_csv(read_text_file(file), file.string(), check_key);
  }
  return batch_manifest_from_json(read_json(file), file.string(), check_key);
}

void check_record_name(const std::string& name, const std::string& context) {
  if (name.empty() || name.size() > 200) {
    throw InvalidArgument(context + ": field 'name' must have 1 to 200 characters");
  }
  for (const char c : name) {
    if (!name_byte(c)) {
      throw InvalidArgument(context + ": field 'name' is '" + name +
                            "'; a name holds only letters, digits, '.', '_' and '-' (it names "
                            "the record's files)");
    }
  }
  if (name.front() == '.' || name.front() == '-') {
    throw InvalidArgument(context + ": field 'name' is '" + name +
                          "'; it may not start with '.' or '-'");
  }
  if (batch_file_name(name)) {
    throw InvalidArgument(context + ": field 'name' is '" + name +
                          "'; summary, timings and names ending in .error are the batch's own "
                          "files");
  }
}

std::vector<std::string> record_names(const std::vector<ManifestRecord>& records) {
  std::vector<std::string> names = derived_names(records);
  std::map<std::string, std::string> first_of;  // name -> context of its first record
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (!records[i].name.empty()) names[i] = records[i].name;
    check_record_name(names[i], records[i].context);
    const auto [first, inserted] = first_of.emplace(names[i], records[i].context);
    if (!inserted) {
      throw InvalidArgument(records[i].context + ": the name '" + names[i] + "' is taken by " +
                            first->second + "; names must be unique (give \"name\")");
    }
  }
  return names;
}

}  // namespace ctid::io

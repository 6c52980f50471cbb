// libFuzzer harness of the batch-manifest reader (io/batch_manifest.h): the same bytes read as
// a JSON manifest and as a CSV manifest. A manifest that was read must hold at least one data
// path per record, none empty or starting with '-' (it would be read as a flag), and its
// record names (io::record_names) must be valid file names and unique; a record without
// "name" must never be refused on its derived name, which is safe by construction.
#include <set>
#include <string>

#include "ctid/io/batch_manifest.h"
#include "ctid/io/json.h"
#include "harness.h"

namespace {

// Stands in for ctid batch's check against ctid fit's flags: a name of lowercase letters,
// digits and '-' passes, anything else is refused as the command line refuses an unknown flag.
void check_flag_like(const std::string& key, const std::string& context) {
  bool ok = !key.empty();
  for (const char c : key)
    ok = ok && ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-');
  if (!ok) throw ctid::InvalidArgument(context + ": field '" + key + "' is not a flag");
}

void check_manifest(const ctid::io::BatchManifest& manifest) {
  for (const ctid::io::ManifestRecord& record : manifest.records) {
    if (record.data.empty()) ctid::fuzz::finding("a record without a data path");
    for (const std::string& path : record.data) {
      if (path.empty() || path.front() == '-') ctid::fuzz::finding("a data path empty or a flag");
    }
  }
  std::vector<std::string> names;
  try {
    names = ctid::io::record_names(manifest.records);
  } catch (const ctid::InvalidArgument& e) {
    // Only a name the manifest gave may be refused: one that is not a file name, or one that
    // two records give.
    std::set<std::string> given;
    bool given_is_bad = false;
    for (const ctid::io::ManifestRecord& record : manifest.records) {
      if (record.name.empty()) continue;
      try {
        ctid::io::check_record_name(record.name, record.context);
      } catch (const ctid::InvalidArgument&) {
        given_is_bad = true;
      }
      given_is_bad = given_is_bad || !given.insert(record.name).second;
    }
    if (!given_is_bad) {
      std::fprintf(stderr, "a derived name was refused: %s\n", e.what());
      std::abort();
    }
    return;
  }
  if (names.size() != manifest.records.size()) ctid::fuzz::finding("a name per record");
  std::set<std::string> seen;
  for (const std::string& name : names) {
    try {
      ctid::io::check_record_name(name, "fuzz");
    } catch (const ctid::InvalidArgument& e) {
      std::fprintf(stderr, "record_names returned a bad name: %s\n", e.what());
      std::abort();
    }
    if (!seen.insert(name).second) ctid::fuzz::finding("record_names returned a name twice");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  ctid::fuzz::refuse_or_use(text, [](std::string_view json_text) {
    check_manifest(ctid::io::batch_manifest_from_json(ctid::io::parse_json(json_text, "in/m.json"),
                                                      "in/m.json", check_flag_like));
  });
  ctid::fuzz::refuse_or_use(text, [](std::string_view csv_text) {
    check_manifest(ctid::io::batch_manifest_from_csv(csv_text, "in/m.csv", check_flag_like));
  });
  return 0;
}

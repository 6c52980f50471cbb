// The record of which flag sets which field, read back when a validation message names a field.
#include "field_flags.h"

#include <map>

namespace ctid::cli {
namespace {

// Per app: field path ("IdentificationOptions.refined_iv.output_interpolation") -> flag.
std::map<const CLI::App*, std::map<std::string, std::string>>& field_flag_records() {
  static std::map<const CLI::App*, std::map<std::string, std::string>> records;
  return records;
}

}  // namespace

void record_field_flag(const CLI::App& app, const std::string& path, const std::string& flag) {
  field_flag_records()[&app][path] = flag;
}

std::string recorded_field_flag(const CLI::App& app, const std::string& type,
                                const std::vector<std::string>& components) {
  const auto found = field_flag_records().find(&app);
  if (found == field_flag_records().end()) return "";
  for (std::size_t j = components.size(); j > 0; --j) {
    std::string path = type;
    for (std::size_t k = 0; k < j; ++k) path += "." + components[k];
    const auto flag = found->second.find(path);
    if (flag == found->second.end()) continue;
    std::string rest;
    for (std::size_t k = j; k < components.size(); ++k) {
      rest += (rest.empty() ? "" : ".") + components[k];
    }
    return rest.empty() ? flag->second : flag->second + " (" + rest + ")";
  }
  return "";
}

namespace field_flags_internal {

// The doc without its closing full stop, as CLI11's help lines are written.
std::string help_text(std::string_view doc) {
  std::string text(doc);
  if (!text.empty() && text.back() == '.') text.pop_back();
  return text;
}

}  // namespace field_flags_internal
}  // namespace ctid::cli

// The structure flags shared by ctid fit and ctid track (structure_flags.h).
#include "structure_flags.h"

#include <algorithm>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "command.h"
#include "ctid/core/error.h"
#include "ctid/io/model_json.h"

namespace ctid::cli {

int parse_count(const std::string& text, const std::string& what) {
  const std::optional<int> value = parse_number<int>(text);
  if (!value || *value < 0) usage_error(what + ": '" + text + "' is not a non-negative integer");
  return *value;
}

std::vector<int> parse_counts(const std::string& text, const std::string& what) {
  std::vector<int> counts;
  std::size_t at = 0;
  while (true) {
    const std::size_t comma = std::min(text.find(',', at), text.size());
    counts.push_back(parse_count(text.substr(at, comma - at), what));
    if (comma == text.size()) return counts;
    at = comma + 1;
  }
}

SubmodelOrder parse_submodel(const std::string& text) {
  const auto commas = std::count(text.begin(), text.end(), ',');
  if (commas < 1 || commas > 2 || text.back() == ',') {
    usage_error("--submodel '" + text + "': expected n,m or n,m,l (poles, zeros, integrators)");
  }
  const std::vector<int> counts = parse_counts(text, "--submodel '" + text + "'");
  if (counts.size() == 3 && counts[2] > io::kMaxIntegrators) {
    usage_error(internal::concat("--submodel '", text, "': ", counts[2],
                                 " integrators; a model document holds at most ",
                                 io::kMaxIntegrators,
                                 " per submodel, so ctid could not read the "
                                 "fitted model back"));
  }
  return SubmodelOrder{counts[0], counts[1], counts.size() == 3 ? counts[2] : 0};
}

ModelStructure model_structure(const StructureFlagValues& f, const CLI::App& app) {
  const bool unfactored = app.count("--poles") > 0;
  const bool submodels = !f.submodels.empty();
  const bool modes = app.count("--modes") > 0;
  const int given = (unfactored ? 1 : 0) + (submodels ? 1 : 0) + (modes ? 1 : 0);
  if (given != 1) {
    usage_error(
        "give one model structure: --poles N --zeros M [--integrators L] (unfactored), "
        "--submodel N,M[,L] (repeated, additive) or --modes K (additive)");
  }
  if (app.count("--zeros") > 0 && !unfactored) usage_error("--zeros needs --poles");
  if (app.count("--integrators") > 0 && !unfactored) {
    usage_error("--integrators goes with --poles; for an additive model write --submodel N,M,L");
  }
  if (!f.model.empty() && (f.model == "additive") == unfactored) {
    usage_error("--model " + f.model +
                " does not match the structure flags (--poles is "
                "unfactored; --submodel and --modes are additive)");
  }
  if (unfactored) {
    if (f.integrators > io::kMaxIntegrators) {
      usage_error(internal::concat("--integrators is ", f.integrators,
                                   "; a model document holds at most ", io::kMaxIntegrators,
                                   ", so ctid could not read the fitted model back"));
    }
    if (app.count("--zeros") == 0) {
      // As MATLAB's tfest: a strictly proper model with a full numerator, said on stderr.
      const int zeros = std::max(f.poles + f.integrators - 1, 0);
      std::cerr << "note: --zeros not given: " << zeros
                << " zeros, one fewer than the poles (as MATLAB's tfest); give --zeros to "
                   "choose\n";
      return ModelStructure::unfactored(f.poles, zeros, f.integrators);
    }
    return ModelStructure::unfactored(f.poles, f.zeros, f.integrators);
  }
  if (submodels) {
    std::vector<SubmodelOrder> orders;
    for (const std::string& text : f.submodels) orders.push_back(parse_submodel(text));
    return ModelStructure::additive(std::move(orders));
  }
  if (f.modes < 1) usage_error("--modes must be at least 1, not " + std::to_string(f.modes));
  return ModelStructure::modes(f.modes);
}

}  // namespace ctid::cli

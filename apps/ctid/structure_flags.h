// The model-structure flags that `ctid fit` and `ctid track` share: --poles N --zeros M
// [--integrators L] (one unfactored transfer function), --submodel N,M[,L] repeated (additive) or
// --modes K, with --model naming the kind, turned into a ModelStructure. Which flags go together
// is checked here (usage errors); what the structure then means is decided by the library.
#pragma once

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "ctid/identification/identification.h"

namespace ctid::cli {

/// `text` as a non-negative integer; a usage error naming `what` otherwise.
int parse_count(const std::string& text, const std::string& what);
/// "a,b,c" as non-negative integers (an empty part is not one); `what` names the flag.
std::vector<int> parse_counts(const std::string& text, const std::string& what);
/// --submodel N,M or N,M,L (poles, zeros, integrators).
SubmodelOrder parse_submodel(const std::string& text);

/// The values of the structure flags (the flags themselves are registered by each command).
struct StructureFlagValues {
  std::string model;  ///< "unfactored" or "additive"; empty: from the structure flags
  int poles = 0;
  int zeros = 0;
  int integrators = 0;
  std::vector<std::string> submodels;
  int modes = 0;
};

/// The structure flags as a ModelStructure; `app` tells which were given (usage errors for
/// none, several, or flags that do not go together).
ModelStructure model_structure(const StructureFlagValues& f, const CLI::App& app);

/// The same for a command's flag struct with members of the same names.
template <class Flags>
ModelStructure model_structure(const Flags& f, const CLI::App& app) {
  return model_structure(
      StructureFlagValues{f.model, f.poles, f.zeros, f.integrators, f.submodels, f.modes}, app);
}

}  // namespace ctid::cli

// The front door of output-only (operational) modal analysis (docs/oma.md):
// identify_output_only runs what `ctid oma` and Python's ctid.oma run, the method
// OmaOptions::method names (SSI-cov, SSI-data, FDD or EFDD; oma/oma.h), with its stabilisation
// diagram, clustering and standard errors; and, for several setups of one structure with shared
// reference channels, their modes merged into global ones (oma/multi_setup.h). The result
// types stay the oma module's.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "ctid/oma/multi_setup.h"
#include "ctid/oma/oma.h"

namespace ctid {

/// Modes of the N x l record `outputs` (no input measured) sampled every `sample_time` seconds,
/// channels named by `channel_names` (empty: y1..yl): oma(outputs, sample_time, options,
/// channel_names), with its input checks (two channels or more, none constant or non-finite,
/// options, orders the Hankel matrix can hold, enough samples); throws InvalidArgument as it
/// does.
OmaResult identify_output_only(const Eigen::MatrixXd& outputs, double sample_time,
                               const OmaOptions& options = {},
                               std::vector<std::string> channel_names = {});

/// The global modes of several setups of one structure (`ctid oma s1.csv s2.csv ...`, Python's
/// ctid.oma_setups): oma_multi_setup(setups, options), with its checks; throws InvalidArgument
/// as it does.
MultiSetupResult identify_output_only(const std::vector<OmaSetup>& setups,
                                      const MultiSetupOptions& options = {});

}  // namespace ctid

// Multi-setup output-only modal analysis: a structure measured in several setups, roving
// sensors moved between them and reference sensors kept in place. Two merges:
// - PoSER (post-separate-estimation re-scaling; Döhler, Andersen and Mevel, IMAC 2010): each
//   setup identified by oma() on its own and the modes merged after: frequencies and damping
//   ratios averaged with inverse-variance weights, each setup's shape scaled onto the first's
//   by the least-squares factor on the reference entries, into one global shape; the standard
//   errors carried through the merge to first order (decision 0059).
// - PreGER (pre-global estimation re-scaling; Döhler and Mevel, "Modular subspace-based system
//   identification from multi-setup measurements", IEEE TAC 2012): each setup's SSI
//   observability matrix moved into the first setup's state basis through the reference rows,
//   the global observability matrix interleaved from them, and one stabilisation diagram and
//   one set of modes from it; standard errors from segments (decision 0062).
#pragma once

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include "ctid/core/fields.h"
#include "ctid/oma/oma.h"

namespace ctid {

/// One setup: its record (N x l, no input) and the names of its l channels. Reference
/// channels are found by name in every setup; every other name belongs to one setup.
struct OmaSetup {
  Eigen::MatrixXd outputs;
  double sample_time = 0.0;
  std::vector<std::string> channel_names;
};

enum class OmaMerge { poser, preger };
inline constexpr std::array<Enumerator<OmaMerge>, 2> oma_merge_enumerators{{
    {OmaMerge::poser, "poser",
     "Post-separate-estimation re-scaling: each setup identified alone, its shapes scaled "
     "onto the first setup's on the reference channels."},
    {OmaMerge::preger, "preger",
     "Pre-global estimation re-scaling: each setup's SSI observability matrix moved into the "
     "first setup's state basis through the reference rows, one identification of the global "
     "matrix (ssi-cov or ssi-data)."},
}};
constexpr std::span<const Enumerator<OmaMerge>> enumerators(OmaMerge) {
  return oma_merge_enumerators;
}

struct MultiSetupOptions {
  /// Each setup's analysis (its reference_channels are set from reference_names).
  OmaOptions oma;
  /// The channels every setup measures, by name (at least one).
  std::vector<std::string> reference_names;
  OmaMerge merge = OmaMerge::poser;
  /// A mode of another setup is the first setup's mode when their frequencies differ by less
  /// than this share and the MAC of their reference entries is at least reference_mac.
  double frequency_tolerance = 0.02;
  double reference_mac = 0.8;

  static constexpr std::string_view type_name = "MultiSetupOptions";
  static constexpr auto fields() {
    using S = MultiSetupOptions;
    return std::tuple{
        field("oma", &S::oma, "OmaOptions of every setup's analysis."),
        field("reference_names", &S::reference_names, "Channels every setup measures."),
        field("merge", &S::merge, "How the setups' modes are merged."),
        field("frequency_tolerance", &S::frequency_tolerance, GreaterThan{0},
              "Largest |df|/f between one mode's frequencies in two setups."),
        field("reference_mac", &S::reference_mac, Between{0, 1, true, true},
              "Smallest MAC of one mode's reference entries in two setups."),
    };
  }
  void validate() const { validate_fields(*this); }
};

/// The merged modes (an OmaResult over the global channels: the references, then each
/// setup's other channels in setup order; PoSER has no stabilisation diagram of its own,
/// PreGER has the global one) and each setup's own analysis.
struct MultiSetupResult {
  OmaResult merged;
  std::vector<OmaResult> setups;

  static constexpr std::string_view type_name = "MultiSetupResult";
  static constexpr auto fields() {
    using S = MultiSetupResult;
    return std::tuple{
        field("merged", &S::merged, "OmaResult of the global modes."),
        field("setups", &S::setups, "OmaResult of each setup alone."),
    };
  }
};

/// The global modes of `setups` (two or more). PoSER: a mode is global when every setup has it
/// (the first setup's modes are matched in the others); the message says how many of the first
/// setup's modes were not. PreGER: the modes of the global observability matrix, with the
/// smallest of the setups' block rows. Throws InvalidArgument for PreGER with fdd or efdd,
/// fewer than two setups, no reference, a
/// reference missing from a setup, sample times that differ by more than 1e-6 of setup 1's (a
/// time column written to ten digits differs by less), a non-reference channel name in
/// two setups, a name twice in one setup, names that do not match the columns, or what oma()
/// refuses in a setup (named). No global mode is an unusable verdict, not an exception.
MultiSetupResult oma_multi_setup(const std::vector<OmaSetup>& setups,
                                 const MultiSetupOptions& options = {});

namespace oma_detail {

/// Which entries of each setup's shape go where in the global shape: `references[s]` the
/// indices of the reference channels in setup s (in reference order), `roving[s]` the
/// global index of each of its channels that is not a reference (-1 for a reference).
struct SetupLayout {
  std::vector<std::vector<int>> references;
  std::vector<std::vector<int>> roving;
  int global_channels = 0;
};

/// PoSER's global shape, not normalised: setup s scaled by α_s = r_s^H r_1 / r_s^H r_s (r_s
/// its reference entries), the reference entries the mean of the scaled setups', each other
/// entry its setup's scaled one.
Eigen::VectorXcd poser_shape(const std::vector<Eigen::VectorXcd>& shapes,
                             const SetupLayout& layout);

/// PreGER's global observability matrix from each setup's (p block rows of its own channels,
/// the same columns). Setup s's reference rows O_ref,s are setup 1's in another state basis, so
/// T_s = O_ref,s^+ O_ref,1 moves O_s into setup 1's basis (exactly, without noise, when the
/// references observe every state). Block row i of the result: setup 1's reference rows, then
/// each other global channel's row i of its setup's O_s T_s.
Eigen::MatrixXd preger_observability(const std::vector<Eigen::MatrixXd>& observabilities,
                                     const SetupLayout& layout);

/// One global mode from each setup's mode of it (setup order): f and ζ the setups' means
/// weighted by 1 / se², their variance 1 / Σ(1 / se²) scaled by ν / (ν - 2) for the se
/// estimated from `blocks` blocks (ν = blocks - 1; the plain mean when ν <= 2 or an se is
/// missing); the shape poser_shape normalised (decision 0030), its standard errors to first
/// order from each setup's (entries taken as independent); MPC and MPD of the merged shape,
/// the fewest supporting orders, setup 1's order.
OmaMode poser_mode(const std::vector<const OmaMode*>& modes, const SetupLayout& layout, int blocks);

}  // namespace oma_detail
}  // namespace ctid

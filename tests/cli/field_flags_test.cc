// Every field of the options structs the commands run has a flag, spelt as its field entry says
// (flag_spelling, core/fields.h; decision 0046), and a value given on the command line reaches
// the field: a bad one comes back from the struct's validate() under the flag's name.
#include <set>
#include <string>
#include <vector>

#include "cli/run_ctid.h"
#include "ctid/core/fields.h"
#include "ctid/delayed_feedback/identification.h"
#include "ctid/estimation/validation.h"
#include "ctid/frf_fit/frf_matrix_fit.h"
#include "ctid/identification/identification.h"
#include "ctid/identification/mimo.h"
#include "ctid/identification/mode_tracking.h"
#include "ctid/identification/structure_scan.h"
#include "ctid/oma/oma.h"
#include "ctid/process_model/process_model.h"
#include "ctid/refined_iv/mimo_srivc.h"
#include "ctid/simulation/time_response.h"

namespace ctid::cli::field_flags_test {
namespace {

using testing::CliTest;
using testing::expect_bad_input;
using ::testing::HasSubstr;

// The long flags `help` lists: "--name" up to a space, comma, '=' or line end.
std::set<std::string> long_flags(const std::string& help) {
  std::set<std::string> flags;
  for (std::size_t at = help.find("--"); at != std::string::npos; at = help.find("--", at + 2)) {
    const std::size_t end = help.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-", at + 2);
    flags.insert(help.substr(at, end - at));
  }
  return flags;
}

// `path` is one of `exceptions` or a field inside one ("two_stage.sensitivity_order").
bool excepted(const std::set<std::string>& exceptions, const std::string& path) {
  for (const std::string& e : exceptions) {
    if (path == e || path.rfind(e + ".", 0) == 0) return true;
  }
  return false;
}

class FieldFlags : public CliTest {
 protected:
  // Every field of S but `exceptions` (path -> why) has its flag in `command --help`.
  template <HasFields S>
  void expect_every_field_a_flag(const std::string& command,
                                 const std::set<std::string>& exceptions = {}) {
    const auto help = ctid({command, "--help"});
    ASSERT_EQ(help.status, 0) << help.err;
    const std::set<std::string> flags = long_flags(help.out);
    int checked = 0;
    for (const FieldFlag& f : field_flags<S>()) {
      if (excepted(exceptions, f.path)) continue;
      EXPECT_EQ(flags.count("--" + f.flag), 1u) << "ctid " << command << " has no --" << f.flag
                                                << " for " << S::type_name << "." << f.path;
      ++checked;
    }
    EXPECT_GT(checked, 0);
  }
};

TEST_F(FieldFlags, FitHasAFlagForEveryIdentificationAndProcessOption) {
  // Constraints are set by name, NAME=VALUE, through --fix, --bound and --dc-gain.
  expect_every_field_a_flag<IdentificationOptions>("fit", {"constraints"});
  // A process model's parameters are set by name, NAME=VALUE, through three flags.
  expect_every_field_a_flag<ProcessModelOptions>("fit", {"parameters"});
  const auto help = ctid({"fit", "--help"}).out;
  for (const char* flag :
       {"--process-start", "--process-fix", "--process-bound", "--fix", "--bound", "--dc-gain"}) {
    EXPECT_THAT(help, HasSubstr(flag));
  }
}

TEST_F(FieldFlags, OmaFitFrfAndFeedbackHaveAFlagForEveryOption) {
  expect_every_field_a_flag<OmaOptions>("oma");
  expect_every_field_a_flag<FrfMatrixFitOptions>("fit-frf");
  // The default shown is the struct's (docs/frf-fit.md quotes it).
  EXPECT_THAT(ctid({"fit-frf", "--help"}).out, HasSubstr("--start-iterations INT=50"));
  // An Eigen vector and matrix have no command-line form (Python and JSON give them).
  expect_every_field_a_flag<FeedbackIdentificationOptions>(
      "feedback", {"recursive.initial_theta", "recursive.initial_covariance_matrix"});
}

// What a window of `ctid track` or a fit of `ctid structure` does not take from the command
// line (decision 0051): questions of the whole record, and one start for structures of
// several orders; the polish and the constraints are ctid fit's (decision 0057).
const std::set<std::string> kWholeRecord = {"identification.delay_scan_samples",
                                            "identification.delay_range",
                                            "identification.two_stage",
                                            "identification.refined_iv.record_delay_samples",
                                            "identification.polish",
                                            "identification.polish_options",
                                            "identification.constraints"};

TEST_F(FieldFlags, TrackStructureValidateStepAndImpulseHaveAFlagForEveryOption) {
  // Several inputs and outputs: the shared-pole estimator's own fields, beside fit's others.
  expect_every_field_a_flag<MimoRefinedIvOptions>("fit");
  expect_every_field_a_flag<TrackingOptions>("track", kWholeRecord);
  expect_every_field_a_flag<MimoTrackingOptions>("track");
  std::set<std::string> scan = {"identification.refined_iv.initial_model"};
  for (const std::string& path : kWholeRecord) {
    if (path != "identification.delay_scan_samples") scan.insert(path);
  }
  expect_every_field_a_flag<StructureScanOptions>("structure", scan);
  expect_every_field_a_flag<ValidationOptions>("validate");
  // The kind is the command's name.
  expect_every_field_a_flag<TimeResponseOptions>("step", {"kind"});
  expect_every_field_a_flag<TimeResponseOptions>("impulse", {"kind"});
  // Today's spellings stay: a default-true flag is turned off by --no-NAME too.
  const auto track = ctid({"track", "--help"}).out;
  EXPECT_THAT(track, HasSubstr("--no-warm-start"));
  EXPECT_THAT(ctid({"step", "--help"}).out, HasSubstr("-t,--final-time"));
}

// The settings two estimators share pass by their fields() lists (core/fields.h): every
// field of RefinedIvOptions that MimoRefinedIvOptions has by name and type, no other.
TEST(SharedFields, TheSharedSettingsPassByName) {
  const std::vector<std::string> shared =
      shared_field_names<MimoRefinedIvOptions, RefinedIvOptions>();
  EXPECT_EQ(shared, (std::vector<std::string>{"max_iterations", "tolerance", "output_interpolation",
                                              "compute_covariance", "noise",
                                              "noise_model_max_order", "initial_conditions"}));
  RefinedIvOptions siso;
  siso.max_iterations = 7;
  siso.tolerance = 1e-6;
  siso.output_interpolation = Hold::zero_order_hold;
  siso.compute_covariance = false;
  siso.noise = NoiseAssumption::white;
  siso.noise_model_max_order = 3;
  siso.initial_conditions = InitialConditions::estimate;
  MimoRefinedIvOptions mimo;
  mimo.direct_term = true;
  mimo.input_delays_samples = {1.5};
  assign_shared_fields(mimo, siso);
  EXPECT_EQ(mimo.max_iterations, 7);
  EXPECT_EQ(mimo.tolerance, 1e-6);
  EXPECT_EQ(mimo.output_interpolation, Hold::zero_order_hold);
  EXPECT_FALSE(mimo.compute_covariance);
  EXPECT_EQ(mimo.noise, NoiseAssumption::white);
  EXPECT_EQ(mimo.noise_model_max_order, 3);
  EXPECT_EQ(mimo.initial_conditions, InitialConditions::estimate);
  // Its own fields keep their values.
  EXPECT_TRUE(mimo.direct_term);
  EXPECT_EQ(mimo.input_delays_samples, std::vector<double>{1.5});
  EXPECT_TRUE(mimo.siso_engine);
}

// The page that lists a command's flags names every generated one (the estimator's flags of
// track and structure are fit's, listed on fit's page).
template <HasFields S>
void expect_documented(const std::string& page, const std::set<std::string>& exceptions = {},
                       const std::string& also = "") {
  std::set<std::string> flags =
      long_flags(testing::slurp(std::string(CTID_SOURCE_DIR) + "/" + page));
  if (!also.empty()) {
    flags.merge(long_flags(testing::slurp(std::string(CTID_SOURCE_DIR) + "/" + also)));
  }
  for (const FieldFlag& f : field_flags<S>()) {
    if (excepted(exceptions, f.path)) continue;
    EXPECT_EQ(flags.count("--" + f.flag), 1u)
        << page << " does not name --" << f.flag << " (" << S::type_name << "." << f.path << ")";
  }
}

TEST(FieldFlagsDocs, EveryGeneratedFlagIsDocumented) {
  // The constraints' flags are written by hand (NAME=VALUE): the page names them.
  expect_documented<IdentificationOptions>("docs/cli-estimation.md", {"constraints"});
  const std::string estimation =
      testing::slurp(std::string(CTID_SOURCE_DIR) + "/docs/cli-estimation.md");
  for (const char* flag : {"`--fix NAME=VALUE`", "`--bound NAME=LOWER:UPPER`", "`--dc-gain K`"}) {
    EXPECT_THAT(estimation, HasSubstr(flag));
  }
  expect_documented<OmaOptions>("docs/oma.md");
  expect_documented<FrfMatrixFitOptions>("docs/frf-fit.md");
  expect_documented<FeedbackIdentificationOptions>(
      "docs/algorithms/feedback-delay.md",
      {"recursive.initial_theta", "recursive.initial_covariance_matrix"});
  expect_documented<MimoRefinedIvOptions>("docs/cli-estimation.md");
  expect_documented<TrackingOptions>("docs/cli.md", kWholeRecord, "docs/cli-estimation.md");
  expect_documented<MimoTrackingOptions>("docs/cli.md", {}, "docs/cli-estimation.md");
  expect_documented<StructureScanOptions>("docs/cli-estimation.md", kWholeRecord);
  expect_documented<ValidationOptions>("docs/cli-estimation.md");
  expect_documented<TimeResponseOptions>("docs/cli.md", {"kind"});
}

// Today's spellings where a field's name differs from its flag.
TEST_F(FieldFlags, FieldsCarryTheSpellingsTheCommandsHaveUsed) {
  const auto spelt = [](const std::vector<FieldFlag>& all, const std::string& path) {
    for (const FieldFlag& f : all) {
      if (f.path == path) return f.flag;
    }
    return std::string("(none)");
  };
  const auto fit = field_flags<IdentificationOptions>();
  EXPECT_EQ(spelt(fit, "refined_iv.output_interpolation"), "interpolation");
  EXPECT_EQ(spelt(fit, "refined_iv.input_delay_samples"), "input-delay-samples");
  EXPECT_EQ(spelt(fit, "delay_scan_samples"), "delay-scan-samples");
  EXPECT_EQ(spelt(fit, "refined_iv.record_history"), "history");
  EXPECT_EQ(spelt(fit, "refined_iv.initial_model"), "initial");
  EXPECT_EQ(spelt(fit, "refined_iv.start_screening_samples"), "start-screening");
  EXPECT_EQ(spelt(fit, "two_stage.sensitivity_order"), "sensitivity-order");
  EXPECT_EQ(spelt(fit, "relocation.min_peak_to_floor"), "relocation-min-peak-to-floor");
  EXPECT_EQ(spelt(field_flags<OmaOptions>(), "modes_near_hz"), "modes-near");
  EXPECT_EQ(spelt(field_flags<FrfMatrixFitOptions>(), "direct_term"), "direct");
  EXPECT_EQ(spelt(field_flags<FeedbackIdentificationOptions>(), "output_error.hold"), "hold");
  EXPECT_EQ(spelt(field_flags<FeedbackIdentificationOptions>(), "iv.hold"), "iv-hold");
  EXPECT_EQ(spelt(field_flags<MimoRefinedIvOptions>(), "direct_term"), "direct");
  EXPECT_EQ(spelt(field_flags<MimoRefinedIvOptions>(), "rank_one_residues"), "rank-one");
  EXPECT_EQ(spelt(field_flags<MimoTrackingOptions>(), "initial_model"), "initial");
  EXPECT_EQ(spelt(field_flags<MimoIdentificationOptions>(), "initial_model"), "initial");
}

// A number, a nested struct's field and a generated flag of each command reach their fields:
// validate() refuses the value, and the message names the flag.
TEST_F(FieldFlags, AValueOnTheCommandLineReachesItsField) {
  write("d.csv", "t,u,y\n0,0,0\n0.1,1,0\n0.2,0,1\n0.3,1,0\n");
  expect_bad_input(
      ctid({"fit", "d.csv", "--poles", "2", "--zeros", "1", "--noise-model-max-order", "0"}), "fit",
      "--noise-model-max-order is 0; it must be >= 1");
  expect_bad_input(ctid({"fit", "d.csv", "--modes", "2", "--relocation-min-peak-to-floor", "0.5"}),
                   "fit", "--relocation-min-peak-to-floor is 0.5; it must be finite and > 1");
  expect_bad_input(ctid({"fit", "d.csv", "--modes", "2", "--relocation-damping-ratios", "0.1,2"}),
                   "fit", "--relocation-damping-ratios[1] is 2; it must be in (0, 1)");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "1:2", "--frequency-tolerance", "0"}),
                   "structure", "--frequency-tolerance is 0; it must be finite and > 0");
  // Several channels: a shared setting reaches the shared-pole estimator through fit's one
  // flag, and an own one through its own.
  expect_bad_input(ctid({"fit", "d.csv", "--input-columns", "u", "--output-columns", "y", "--modes",
                         "1", "--max-iterations", "0"}),
                   "fit", "--max-iterations is 0; it must be >= 1");
  expect_bad_input(ctid({"track", "d.csv", "--input-columns", "u", "--output-columns", "y",
                         "--modes", "1", "--window", "1", "--min-mac", "2"}),
                   "track", "--min-mac is 2; it must be in [0, 1]");
  const std::string model = testing::CliTest::example("gonzalez_6_1_open_loop.json");
  expect_bad_input(ctid({"validate", model, "d.csv", "--max-lag", "0"}), "validate",
                   "--max-lag is 0; it must be >= 1");
  expect_bad_input(ctid({"step", model, "--confidence", "1"}), "step",
                   "--confidence is 1; it must be in (0, 1)");
  write("h.csv", "frequency_hz\n1\n");
  expect_bad_input(ctid({"fit-frf", "h.csv", "--modes", "2", "--start-iterations", "0"}), "fit-frf",
                   "--start-iterations is 0; it must be >= 1");
}

TEST_F(FieldFlags, AnEnumerationTakesItsNamesAndAnOptionalOneReachesItsField) {
  write("d.csv", "t,u,y\n0,0,0\n0.1,1,0\n0.2,0,1\n0.3,1,0\n");
  // An enumeration's words are checked as the command line is read.
  expect_bad_input(ctid({"fit", "d.csv", "--poles", "2", "--zeros", "1", "--noise", "pink"}), "fit",
                   "--noise is 'pink'; it must be white or coloured");
  expect_bad_input(ctid({"fit", "d.csv", "--modes", "2", "--relocation-criterion", "aic"}), "fit",
                   "--relocation-criterion is 'aic'; it must be projected_output_error or "
                   "output_error");
  // iv.hold (optional) must agree with output_error.hold (--hold, foh by default).
  std::string csv = "t,u,y\n";
  for (int k = 0; k < 200; ++k) {
    csv += std::to_string(0.05 * k) + "," + std::to_string(k % 7 == 0 ? 1 : 0) + "," +
           std::to_string(0.01 * (k % 5)) + "\n";
  }
  write("loop.csv", csv);
  const auto r = ctid({"feedback", "loop.csv", "--forward-order", "1", "--feedback-order", "1",
                       "--delay", "0.1", "--iv-hold", "zoh"});
  expect_bad_input(r, "feedback", "--iv-hold is zero_order_hold; it must be empty or");
}

}  // namespace
}  // namespace ctid::cli::field_flags_test

// The data flags shared by fit, validate and frf (apps/ctid/data_flags.h) on the shipped real
// records and on small written files: time stamps printed to few digits, -T overriding a time
// column, the declared input hold, and preprocessing (--detrend, --rows, --time, --decimate)
// recorded in the result and refused with one line when it cannot apply.
#include <cmath>
#include <cstdio>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/core/format.h"
#include "ctid/io/csv.h"
#include "ctid/io/json.h"

namespace ctid::cli::data_flags_test {
namespace {

using ::testing::HasSubstr;

const std::string kData = std::string(CTID_SOURCE_DIR) + "/data/";

using testing::expect_bad_input;

// y follows a first-order lag of u plus offsets 5 and 3, stamps printed with `digits`
// significant digits.
std::string lag_csv(int n, double h, int digits, const std::string& preamble = "") {
  std::string text = preamble + "t,u,y\n";
  double y = 0.0;
  char line[128];
  for (int k = 0; k < n; ++k) {
    const double u = std::sin(0.37 * k) + (k % 7 < 3 ? 1.0 : -1.0);
    std::snprintf(line, sizeof line, "%.*g,%.17g,%.17g\n", digits, k * h, u + 5.0, y + 3.0);
    text += line;
    y = std::exp(-h) * y + (1.0 - std::exp(-h)) * u;
  }
  return text;
}

class DataFlags : public testing::CliTest {};

TEST_F(DataFlags, DryerValidatesFarBetterWithItsMeansRemoved) {
  const std::string dryer = kData + "daisy_dryer_ljung/dryer.csv";
  const std::vector<std::string> columns = {"--time-column",   "t_s_assumed_0.08",
                                            "--input-column",  "u_heater_voltage",
                                            "--output-column", "y_outlet_temperature"};
  double fit[2] = {0.0, 0.0};
  const char* detrend[2] = {"none", "mean"};
  for (int i = 0; i < 2; ++i) {
    std::vector<std::string> args = {"fit",
                                     dryer,
                                     "--poles",
                                     "2",
                                     "--zeros",
                                     "0",
                                     "--input-delay-samples",
                                     "3",
                                     "--detrend",
                                     detrend[i],
                                     "--model-output",
                                     "m.json",
                                     "-o",
                                     "fit.json",
                                     "--force"};
    args.insert(args.end(), columns.begin(), columns.end());
    const auto fitted = ctid(args);
    ASSERT_EQ(fitted.status, 0) << fitted.err;
    const nlohmann::json document = io::read_json(path("fit.json"));
    EXPECT_EQ(document["data"]["preprocessing"]["detrend"], detrend[i]);
    std::vector<std::string> check = {"validate", "m.json", dryer,         "--detrend",
                                      detrend[i], "-o",     "report.json", "--force"};
    check.insert(check.end(), columns.begin(), columns.end());
    const auto validated = ctid(check);
    ASSERT_EQ(validated.status, 0) << validated.err;
    fit[i] = io::read_json(path("report.json"))["fit_percent"];
    if (i == 0) {
      EXPECT_THAT(fitted.err, HasSubstr("output mean 4.8901 is 5.9 x its standard deviation"));
    } else {
      EXPECT_THAT(fitted.out, HasSubstr("preprocessing: rows 0:1000, means removed (u 5, y 4.89"));
      EXPECT_NEAR(document["data"]["preprocessing"]["input_offset"].get<double>(), 5.0, 0.01);
      EXPECT_EQ(fitted.err, "");
    }
  }
  // Measured: 52.8 % raw, 84.3 % with the means removed (n = 2, m = 0, delay 3).
  EXPECT_LT(fit[0], 60.0);
  EXPECT_GT(fit[1], 80.0);
}

TEST_F(DataFlags, DetrendFitCarriesTheEstimationMeansToTheValidationRecord) {
  // Fitted on the dryer's first 600 samples with their means removed, judged on the last 400:
  // --detrend fit removes the estimation record's means (the validation record's own differ),
  // which is validating by hand on a file with those means subtracted, number for number.
  const std::string dryer = kData + "daisy_dryer_ljung/dryer.csv";
  const std::vector<std::string> columns = {"--time-column",   "t_s_assumed_0.08",
                                            "--input-column",  "u_heater_voltage",
                                            "--output-column", "y_outlet_temperature"};
  std::vector<std::string> fit = {
      "fit", dryer,    "--poles", "2",         "--zeros", "0",  "--input-delay-samples",
      "3",   "--rows", "0:600",   "--detrend", "mean",    "-o", "fit.json"};
  fit.insert(fit.end(), columns.begin(), columns.end());
  ASSERT_EQ(ctid(fit).status, 0);
  const nlohmann::json trend = io::read_json(path("fit.json"))["data"]["preprocessing"];
  std::vector<std::string> check = {
      "validate", "fit.json", dryer, "--rows", "600:", "--detrend", "fit", "-o", "report.json"};
  check.insert(check.end(), columns.begin(), columns.end());
  const auto validated = ctid(check);
  ASSERT_EQ(validated.status, 0) << validated.err;
  const nlohmann::json report = io::read_json(path("report.json"));
  EXPECT_EQ(report["data"]["preprocessing"]["output_offset"], trend["output_offset"]);
  const double mse = report["mean_squared_error"];
  EXPECT_THAT(validated.out,
              HasSubstr("RMS error " + format_brief(std::sqrt(mse)) + " (output units)"));

  const io::CsvTable table = io::read_csv(dryer);
  const double u0 = trend["input_offset"];
  const double y0 = trend["output_offset"];
  std::string text = "t,u,y\n";
  for (int k = 600; k < table.rows(); ++k) {
    text += format_round_trip(table.column("t_s_assumed_0.08")(k)) + "," +
            format_round_trip(table.column("u_heater_voltage")(k) - u0) + "," +
            format_round_trip(table.column("y_outlet_temperature")(k) - y0) + "\n";
  }
  write("by_hand.csv", text);
  ASSERT_EQ(ctid({"validate", "fit.json", "by_hand.csv", "-o", "by_hand.json"}).status, 0);
  const nlohmann::json by_hand = io::read_json(path("by_hand.json"));
  EXPECT_NEAR(report["fit_percent"].get<double>(), by_hand["fit_percent"].get<double>(), 1e-9);
  EXPECT_NEAR(mse, by_hand["mean_squared_error"].get<double>(), 1e-12);

  // The validation record's own means instead: another operating point, a different score.
  check[6] = "mean";
  check[8] = "own.json";
  ASSERT_EQ(ctid(check).status, 0);
  EXPECT_NE(io::read_json(path("own.json"))["data"]["preprocessing"]["output_offset"],
            trend["output_offset"]);

  // A plain model file has no trend to carry: one clear line.
  ASSERT_EQ(ctid({"fit", dryer, "--poles", "1", "--zeros", "0", "--model-output", "m.json", "-q",
                  "--time-column", "t_s_assumed_0.08", "--input-column", "u_heater_voltage",
                  "--output-column", "y_outlet_temperature"})
                .status,
            0);
  check[1] = "m.json";
  check[6] = "fit";
  check[8] = "plain.json";
  const auto plain = ctid(check);
  EXPECT_EQ(plain.status, 2);
  EXPECT_THAT(plain.err, HasSubstr("m.json holds no preprocessing record"));
}

TEST_F(DataFlags, ShippedFlexibleStructureStampsAreUniform) {
  const auto r =
      ctid({"frf", kData + "daisy_flexible_structure/flexible_structure.csv", "--time-column",
            "t_s", "--input-column", "u1_force", "--output-column", "y1_acc", "-o", "frf.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.err, "");
  const nlohmann::json document = io::read_json(path("frf.json"));
  EXPECT_NEAR(document["data"]["sample_time"].get<double>(), 1.0 / 1024.0, 1e-8 / 1024.0);
}

TEST_F(DataFlags, StampsToFiveDigitsAreAcceptedAndSampleTimeOverridesThem) {
  const std::string five = write("five.csv", lag_csv(2000, 1.0 / 1024.0, 5));
  // (An FRF, not a fit: what is tested is how the stamps are read, and a first-order fit of
  // this record after removing its means is rightly judged unusable.)
  const std::vector<std::string> read = {"frf", five, "-o", "r.json", "-q", "--force"};
  const auto r = ctid(read);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NEAR(io::read_json(path("r.json"))["data"]["sample_time"].get<double>(), 1.0 / 1024.0,
              1e-6);
  // -T wins over the time column, with a note.
  std::vector<std::string> override = read;
  override.insert(override.end(), {"-T", "0.001"});
  const auto t = ctid(override);
  ASSERT_EQ(t.status, 0) << t.err;
  EXPECT_THAT(t.err, HasSubstr("note: --sample-time 0.001 s overrides the time column 't'"));
  EXPECT_EQ(io::read_json(path("r.json"))["data"]["sample_time"].get<double>(), 0.001);
  // A missing row is a gap, named with the step found.
  std::string gapped = lag_csv(200, 0.1, 6);
  const std::size_t row = gapped.find("\n10,");
  gapped.erase(row, gapped.find('\n', row + 1) - row);
  const std::string gap = write("gap.csv", gapped);
  expect_bad_input(ctid({"fit", gap, "--poles", "1", "--zeros", "0"}), "fit",
                   "time stamps are not uniform: sample 99 (t = 9.9 s)");
  EXPECT_EQ(ctid({"frf", gap, "-T", "0.1", "-q"}).status, 0);
  EXPECT_THAT(ctid({"fit", gap, "--poles", "1", "--zeros", "0"}).err,
              HasSubstr("--resample H moves irregular stamps onto a grid"));
  // --resample moves the stamps onto a grid (the held input at its last value, the output
  // linearly across the gap), with a note; with -T it is refused.
  const auto resampled = ctid({"frf", gap, "--resample", "0.1", "-o", "g.json", "--force", "-q"});
  ASSERT_EQ(resampled.status, 0) << resampled.err;
  EXPECT_THAT(resampled.err, HasSubstr(gap + ": 199 time stamps resampled onto h = 0.1 s (200 "
                                             "samples)"));
  expect_bad_input(ctid({"frf", gap, "--resample", "0.1", "-T", "0.1"}), "frf",
                   "give --resample or --sample-time, not both");
}

TEST_F(DataFlags, DeclaredInputHoldIsUsedAndAContradictingFlagRefused) {
  const std::string declared = write("foh.csv", lag_csv(300, 0.1, 17, "# input_hold: foh\n"));
  const auto r = ctid(
      {"fit", declared, "--poles", "1", "--zeros", "0", "--detrend", "mean", "-o", "r.json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(io::read_json(path("r.json"))["data"]["input_hold"], "first_order_hold");
  expect_bad_input(
      ctid({"fit", declared, "--poles", "1", "--zeros", "0", "--input-hold", "zoh"}), "fit",
      "--input-hold zoh contradicts " + declared + ":1, which declares input_hold: foh");
  expect_bad_input(ctid({"fit", declared, "--poles", "1", "--zeros", "0", "--input-hold", "cubic"}),
                   "fit", "--input-hold 'cubic': expected zoh or foh");
}

TEST_F(DataFlags, RangesAndDecimationAreRecordedAndBadOnesRefused) {
  const std::string csv = write("d.csv", lag_csv(400, 0.1, 17));
  const auto r = ctid({"fit", csv, "--poles", "1", "--zeros", "0", "--detrend", "linear", "--rows",
                       "100:", "--decimate", "2", "-o", "r.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json data = io::read_json(path("r.json"))["data"];
  EXPECT_EQ(data["samples"], 150);
  EXPECT_DOUBLE_EQ(data["sample_time"].get<double>(), 0.2);
  EXPECT_EQ(data["preprocessing"]["first_row"], 100);
  EXPECT_EQ(data["preprocessing"]["decimate"], 2);
  EXPECT_THAT(r.out, HasSubstr("preprocessing: rows 100:400, lines removed"));

  const auto bad = [&](std::vector<std::string> flags, const std::string& message) {
    std::vector<std::string> args = {"fit", csv, "--poles", "1", "--zeros", "0"};
    args.insert(args.end(), flags.begin(), flags.end());
    expect_bad_input(ctid(args), "fit", message);
  };
  bad({"--detrend", "mean", "--rows", "3:4"},
      csv + ": rows 3:4 keeps 1 sample; detrend mean needs at least 2");
  bad({"--rows", "300:500"}, "rows 300:500 lie outside the record's 400 rows");
  bad({"--rows", "50:50"}, "--rows (first) is 50 and");
  bad({"--rows", "a:5"}, "--rows 'a:5': 'a' is not a row number");
  bad({"--time", "100:200"}, "time 100:200 s keeps no sample of the record from 0 to 39.9 s");
  bad({"--time", "1:2", "--rows", "1:5"}, "give --rows or --time, not both");
  bad({"--decimate", "0"}, "--decimate is 0; it must be >= 1");
  bad({"--decimate", "400"}, "decimate 400 leaves 1 sample of the 400 kept");
}

}  // namespace
}  // namespace ctid::cli::data_flags_test

// ctid oma: the DaISy flexible structure used output-only (exit 0, a summary table, an
// oma_result document that io::read_result reads back; by ssi-cov and fdd), a record with no
// resonance (exit 3, the verdict), and bad usage (exit 2, one line naming the flag).
#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/documents.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "support/sanitizers.h"

namespace ctid::cli::oma_test {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class OmaCommand : public testing::CliTest {
 protected:
  std::string flexible() const {
    return std::string(CTID_SOURCE_DIR) + "/data/daisy_flexible_structure/flexible_structure.csv";
  }
  // Three channels of two lightly damped resonances (5 and 12 Hz, 2 % damping, each an AR(2)
  // process driven by white noise) plus sensor noise, h = 0.01 s.
  std::string two_modes() const { return resonances("two_modes.csv", "c", -0.8, 0.6, 10); }
  // One setup of a survey (decision 0059): the resonances of two_modes, each setup its own
  // excitation; references a and b as in two_modes, and one roving channel `name` with the
  // modal amplitudes (c5, c12).
  std::string setup(const std::string& name, double c5, double c12, unsigned seed) const {
    return resonances(name + ".csv", name, c5, c12, seed);
  }
  // Columns t, a, b and `third`: a = x5 + x12, b = 0.5 x5 - x12, third = c5 x5 + c12 x12, each
  // with sensor noise of 0.3, x5 and x12 the two resonances.
  std::string resonances(const std::string& file, const std::string& third, double c5, double c12,
                         unsigned seed) const {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    const double h = 0.01;
    double a[2][2];
    const double hz[2] = {5.0, 12.0};
    for (int i = 0; i < 2; ++i) {
      const double w = 2.0 * 3.141592653589793 * hz[i];
      const double radius = std::exp(-0.02 * w * h);
      a[i][0] = 2.0 * radius * std::cos(w * h * std::sqrt(1.0 - 0.02 * 0.02));
      a[i][1] = -radius * radius;
    }
    double x[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
    std::ostringstream csv;
    csv << "t,a,b," << third << "\n";
    for (int k = -500; k < 12000; ++k) {
      for (int i = 0; i < 2; ++i) {
        const double next = a[i][0] * x[i][0] + a[i][1] * x[i][1] + normal(rng);
        x[i][1] = x[i][0];
        x[i][0] = next;
      }
      if (k < 0) continue;
      csv << k * h << "," << x[0][0] + x[1][0] + 0.3 * normal(rng) << ","
          << 0.5 * x[0][0] - x[1][0] + 0.3 * normal(rng) << ","
          << c5 * x[0][0] + c12 * x[1][0] + 0.3 * normal(rng) << "\n";
    }
    return write(file, csv.str());
  }
  // Three channels of independent white noise: no resonance.
  std::string white_noise() const {
    std::mt19937_64 rng(9);
    std::normal_distribution<double> normal;
    std::ostringstream csv;
    csv << "t,a,b,c\n";
    for (int k = 0; k < 4000; ++k) {
      csv << k * 0.01 << "," << normal(rng) << "," << normal(rng) << "," << normal(rng) << "\n";
    }
    return write("noise.csv", csv.str());
  }
};

TEST_F(OmaCommand, FlexibleStructureWritesTheModesAndTheDocument) {
  CTID_SKIP_UNDER_SANITIZERS(
      "the same analysis runs in OmaFlexibleStructure.WellExcitedModesAgreeWithTheInputOutputFit, "
      "and NoResonanceExitsThreeWithTheVerdict runs the command's whole path");
  const auto r = ctid({"oma", flexible(), "--output-columns", "y1_acc:y28_acc", "--time-column",
                       "t_s", "--max-order", "60", "--block-rows", "30", "--uncertainty-blocks",
                       "0", "-o", "oma.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid oma: ssi-cov on"));
  EXPECT_THAT(r.out, HasSubstr("28 channels"));
  EXPECT_THAT(r.out, HasSubstr("verdict: usable"));
  const io::ResultDocument doc = io::read_result(path("oma.json"));
  const auto* result = std::get_if<OmaResult>(&doc);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(result->channels.size(), 28u);
  EXPECT_FALSE(result->modes.empty());
  EXPECT_FALSE(result->stabilisation.empty());
  EXPECT_EQ(result->modes.front().shape_real.size(), 28u);
}

// ssi-data on the same record: its name in the summary and the document, the table with orders.
TEST_F(OmaCommand, SsiDataRunsOnTheFlexibleStructure) {
  CTID_SKIP_UNDER_SANITIZERS(
      "OmaFlexibleStructure.SsiDataWellExcitedModesAgreeWithTheInputOutputFit runs the same "
      "analysis");
  const auto r = ctid({"oma", flexible(), "--output-columns", "y1_acc:y28_acc", "--time-column",
                       "t_s", "--method", "ssi-data", "--max-order", "40", "--block-rows", "20",
                       "--uncertainty-blocks", "0", "-o", "data.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid oma: ssi-data on"));
  EXPECT_THAT(r.out, HasSubstr("orders"));
  const io::ResultDocument doc = io::read_result(path("data.json"));
  const auto* result = std::get_if<OmaResult>(&doc);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(result->method, OmaMethod::ssi_data);
  EXPECT_FALSE(result->modes.empty());
  EXPECT_FALSE(result->stabilisation.empty());
}

// plscf (decision 0066) on the two resonances: both modes within 1 % with segment standard
// errors, the orders column, the method in the document, and the PreGER merge refusing it.
TEST_F(OmaCommand, PlscfFindsBothResonances) {
  const std::string data = two_modes();
  const auto r = ctid({"oma", data, "--method", "plscf", "--max-order", "12", "-o", "p.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid oma: plscf on"));
  EXPECT_THAT(r.out, HasSubstr("polynomial orders 1..12"));
  EXPECT_THAT(r.out, HasSubstr("orders"));
  const io::ResultDocument doc = io::read_result(path("p.json"));
  const auto* result = std::get_if<OmaResult>(&doc);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(result->method, OmaMethod::plscf);
  ASSERT_EQ(result->modes.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    const double f = i == 0 ? 5.0 : 12.0;
    EXPECT_NEAR(result->modes[static_cast<std::size_t>(i)].frequency_hz, f, 0.01 * f);
    EXPECT_GT(result->modes[static_cast<std::size_t>(i)].frequency_hz_std, 0.0);
  }
  testing::expect_bad_input(
      ctid({"oma", setup("s1", 0.3, 0.8, 31), setup("s2", 0.9, -0.4, 32), "--reference-columns",
            "a,b", "--merge", "preger", "--method", "plscf"}),
      "oma", "plscf has no observability matrix");
}

// --uncertainty: perturbation (the default for ssi-cov) says so in the summary; segments gives
// the same modes with other standard errors; a bad name is a usage error naming the flag.
TEST_F(OmaCommand, UncertaintyChoosesHowTheStandardErrorsAreComputed) {
  const std::string data = two_modes();
  const auto first = ctid({"oma", data, "--output-columns", "a:c", "--max-order", "12",
                           "--block-rows", "12", "-o", "perturbation.json"});
  ASSERT_EQ(first.status, 0) << first.err << first.out;
  EXPECT_THAT(first.out, HasSubstr("first-order perturbation standard errors from 10 blocks"));
  const auto second =
      ctid({"oma", data, "--output-columns", "a:c", "--max-order", "12", "--block-rows", "12",
            "--uncertainty", "segments", "-o", "segments.json"});
  ASSERT_EQ(second.status, 0) << second.err;
  EXPECT_THAT(second.out, Not(HasSubstr("perturbation")));
  const io::ResultDocument a = io::read_result(path("perturbation.json"));
  const io::ResultDocument b = io::read_result(path("segments.json"));
  const auto* pa = std::get_if<OmaResult>(&a);
  const auto* pb = std::get_if<OmaResult>(&b);
  ASSERT_TRUE(pa != nullptr && pb != nullptr);
  ASSERT_EQ(pa->modes.size(), 2u);
  ASSERT_EQ(pb->modes.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(pa->modes[i].frequency_hz, pb->modes[i].frequency_hz);
    EXPECT_EQ(pa->modes[i].damping_ratio, pb->modes[i].damping_ratio);
    EXPECT_GT(pa->modes[i].frequency_hz_std, 0.0);
    EXPECT_GT(pa->modes[i].damping_ratio_std, 0.0);
    EXPECT_NE(pa->modes[i].frequency_hz_std, pb->modes[i].frequency_hz_std);
  }
  const auto bad = ctid({"oma", data, "--output-columns", "a:c", "--uncertainty", "bootstrap"});
  EXPECT_EQ(bad.status, 2);
  EXPECT_THAT(bad.err, HasSubstr("--uncertainty is 'bootstrap'"));
}

TEST_F(OmaCommand, NoResonanceExitsThreeWithTheVerdict) {
  const auto r = ctid({"oma", white_noise(), "--output-columns", "a:c", "--max-order", "12"});
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_THAT(r.out, HasSubstr("no mode found"));
}

// fdd: the table has no orders column and a "-" for the damping it does not estimate; the
// document reads back with NaN damping (null in JSON).
TEST_F(OmaCommand, FddPrintsFrequenciesAndWritesADocumentWithoutDamping) {
  const auto r = ctid({"oma", flexible(), "--output-columns", "y1_acc:y28_acc", "--time-column",
                       "t_s", "--method", "fdd", "--segment-length", "1024", "-o", "fdd.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid oma: fdd on"));
  EXPECT_THAT(r.out, HasSubstr("(1024-sample segments, 15 averaged)"));
  EXPECT_THAT(r.out, Not(HasSubstr("orders")));
  EXPECT_THAT(r.out, HasSubstr("    -    "));
  const io::ResultDocument doc = io::read_result(path("fdd.json"));
  const auto* result = std::get_if<OmaResult>(&doc);
  ASSERT_NE(result, nullptr);
  EXPECT_EQ(result->method, OmaMethod::fdd);
  ASSERT_FALSE(result->modes.empty());
  EXPECT_TRUE(std::isnan(result->modes.front().damping_ratio));
  EXPECT_TRUE(result->stabilisation.empty());
}

// The preprocessing flags of ctid fit: the summary and the document say what was done, and
// scaling every channel by 1000 changes no frequency or damping (to rounding).
TEST_F(OmaCommand, PreprocessingIsAppliedAndRecorded) {
  const std::vector<std::string> base = {
      "oma",           flexible(), "--output-columns", "y1_acc:y28_acc",
      "--time-column", "t_s",      "--method",         "efdd"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return ctid(args);
  };
  const auto r =
      with({"--rows", "0:8000", "--decimate", "2", "--detrend", "linear", "-o", "prep.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("4000 samples"));
  EXPECT_THAT(r.out, HasSubstr("preprocessing: rows 0:8000, each channel's line removed, "
                               "decimated by 2, N = 4000"));
  const nlohmann::json doc = nlohmann::json::parse(std::ifstream(path("prep.json")));
  EXPECT_EQ(doc["data"]["preprocessing"]["samples"], 4000);
  EXPECT_EQ(doc["data"]["preprocessing"]["detrend"], "linear");

  ASSERT_EQ(with({"-o", "plain.json"}).status, 0);
  ASSERT_EQ(with({"--scale-output", "1000", "-o", "scaled.json"}).status, 0);
  const auto plain = std::get<OmaResult>(io::read_result(path("plain.json")));
  const auto scaled = std::get<OmaResult>(io::read_result(path("scaled.json")));
  ASSERT_EQ(plain.modes.size(), scaled.modes.size());
  for (std::size_t i = 0; i < plain.modes.size(); ++i) {
    EXPECT_NEAR(scaled.modes[i].frequency_hz, plain.modes[i].frequency_hz,
                1e-9 * plain.modes[i].frequency_hz);
  }
}

TEST_F(OmaCommand, PlotDrawsTheStabilisationDiagram) {
  if (testing::python_package().empty()) {
    GTEST_SKIP() << "the ctid Python package is not built (CTID_BUILD_PYTHON=OFF); set "
                    "CTID_PYTHONPATH to test --plot";
  }
  const std::vector<std::string> args = {
      "oma", white_noise(), "--output-columns", "a:c", "--max-order", "12", "--plot", "figures"};
  const auto r = ctid(args);
  EXPECT_EQ(r.status, 3) << r.err;  // no mode: the diagram is drawn all the same
  testing::expect_png(path("figures") / "stabilisation.png");
  EXPECT_THAT(r.out, HasSubstr("wrote figures/stabilisation.png"));
  EXPECT_FALSE(std::filesystem::exists(path("figures") / "shapes.png"));  // no mode to draw
  // Modes found: their shapes and auto-MAC beside the diagram.
  const auto modes = ctid({"oma", two_modes(), "--max-order", "12", "--plot", "found"});
  EXPECT_EQ(modes.status, 0) << modes.err;
  for (const char* figure : {"stabilisation.png", "shapes.png", "mac.png"}) {
    testing::expect_png(path("found") / figure);
  }
  testing::expect_bad_input(ctid(args), "oma", "stabilisation.png: file exists");
  // On a sensor geometry (decision 0063): the shapes deform the wireframe of a, b and c.
  write("sensors.csv", "channel,x,y\na,0,0\nb,1,0\nc,2,0\n");
  write("lines.csv", "from,to\na,b\nb,c\n");
  const auto drawn =
      ctid({"oma", two_modes(), "--max-order", "12", "--plot", "wireframe", "--geometry",
            path("sensors.csv").string(), "--geometry-lines", path("lines.csv").string()});
  EXPECT_EQ(drawn.status, 0) << drawn.err;
  testing::expect_png(path("wireframe") / "shapes.png");
  testing::expect_bad_input(
      ctid({"oma", two_modes(), "--geometry", path("sensors.csv").string()}), "oma",
      "--geometry draws shapes.png on the sensors' wireframe: give --plot DIR");
  write("bad.csv", "channel,x,y\nq,0,0\n");
  testing::expect_bad_input(ctid({"oma", two_modes(), "--max-order", "12", "--plot", "refused",
                                  "--geometry", path("bad.csv").string()}),
                            "oma", "the geometry's channel 'q' is not one of");
}

// The merged document of setup("c", -0.8, 0.6) and setup("d", 0.3, 0.9): two modes whose shapes
// over a, b, c, d are the modal amplitudes of every channel (MAC >= 0.99 with the real ones).
void expect_the_setups_modal_amplitudes(const nlohmann::json& doc) {
  const double expected[2][4] = {{1.0, 0.5, -0.8, 0.3}, {1.0, -1.0, 0.6, 0.9}};
  ASSERT_EQ(doc["modes"].size(), 2u);
  for (int i = 0; i < 2; ++i) {
    std::complex<double> dot = 0.0;
    double shape = 0.0, truth = 0.0;
    for (int j = 0; j < 4; ++j) {
      const std::complex<double> v(doc["modes"][i]["shape_real"][j].get<double>(),
                                   doc["modes"][i]["shape_imag"][j].get<double>());
      dot += v * expected[i][j];
      shape += std::norm(v);
      truth += expected[i][j] * expected[i][j];
    }
    EXPECT_GE(std::norm(dot) / (shape * truth), 0.99) << i;
  }
}

// Two setups sharing a and b, c and d roving: one document over a, b, c, d whose shapes are the
// modal amplitudes of every channel.
TEST_F(OmaCommand, SeveralFilesAreSetupsMergedIntoGlobalModes) {
  const std::string one = setup("c", -0.8, 0.6, 21);
  const std::string two = setup("d", 0.3, 0.9, 22);
  const auto r = ctid(
      {"oma", one, two, "--reference-columns", "a,b", "--max-order", "12", "-o", "merged.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("PoSER merge of 2 setups: 2 modes found in every setup"));
  const nlohmann::json doc = io::read_json(path("merged.json"));
  EXPECT_EQ(doc["channels"], nlohmann::json({"a", "b", "c", "d"}));
  ASSERT_EQ(doc["setups"].size(), 2u);
  EXPECT_EQ(doc["setups"][1]["data"]["file"], two);
  ASSERT_TRUE(std::holds_alternative<OmaResult>(io::read_result(path("merged.json"))));
  expect_the_setups_modal_amplitudes(doc);
  testing::expect_bad_input(ctid({"oma", one, two}), "oma",
                            "several files are setups of one structure: give --reference-columns");
  testing::expect_bad_input(
      ctid({"oma", one, two, "--reference-columns", "a,b", "--output-columns", "a:c"}), "oma",
      "--output-columns is for one file");
  testing::expect_bad_input(
      ctid({"oma", one, two, "--reference-columns", "a,c"}), "oma",
      "reference channel 'c' is missing from setup 2 (its channels: a, b, d)");
  testing::expect_bad_input(ctid({"oma", one, two, "--reference-columns", "a,b", "--merge", "x"}),
                            "oma", "--merge is 'x'; it must be poser or preger");
}

// The same two setups merged by PreGER (decision 0062): one identification of the global
// observability matrix, its own stabilisation diagram beside each setup's, the same shapes.
TEST_F(OmaCommand, PregerMergesTheSetupsInOneIdentification) {
  const std::string one = setup("c", -0.8, 0.6, 21);
  const std::string two = setup("d", 0.3, 0.9, 22);
  std::vector<std::string> args = {"oma",    one,           two,          "--reference-columns",
                                   "a,b",    "--max-order", "12",         "--merge",
                                   "preger", "-o",          "merged.json"};
  const bool plots = !testing::python_package().empty();
  if (plots) args.insert(args.end(), {"--plot", "figures"});
  const auto r = ctid(args);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("PreGER merge of 2 setups: 2 mode(s) from orders 2..12"));
  const nlohmann::json doc = io::read_json(path("merged.json"));
  EXPECT_EQ(doc["channels"], nlohmann::json({"a", "b", "c", "d"}));
  EXPECT_FALSE(doc["stabilisation"].empty());
  expect_the_setups_modal_amplitudes(doc);
  for (int i = 0; i < 2; ++i) EXPECT_GT(doc["modes"][i]["frequency_hz_std"].get<double>(), 0.0);
  if (plots) {
    for (const char* figure : {"stabilisation.png", "stabilisation_setup1.png",
                               "stabilisation_setup2.png", "shapes.png", "mac.png"}) {
      testing::expect_png(path("figures") / figure);
    }
  }
  testing::expect_bad_input(
      ctid({"oma", one, two, "--reference-columns", "a,b", "--merge", "preger", "--method", "fdd"}),
      "oma", "the PreGER merge needs an SSI method (ssi-cov or ssi-data)");
}

// `ctid track --output-only` (decision 0060): the two resonances followed through three
// windows of 40 s, the document, the table and the refusals.
TEST_F(OmaCommand, TrackOutputOnlyFollowsTheModesThroughTheWindows) {
  const std::string data = two_modes();
  const auto r = ctid({"track", data, "--output-only", "--output-columns", "a:c", "--window", "40",
                       "--max-order", "20", "--block-rows", "20", "-o", "tracking.json", "--table",
                       "tracking.csv"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("ctid track: 3 windows of 40 s (4000 samples, step 4000)"));
  EXPECT_THAT(r.out, HasSubstr("3 outputs, 0 inputs"));
  EXPECT_THAT(r.out, HasSubstr("usable windows: 3 of 3"));
  const nlohmann::json doc = io::read_json(path("tracking.json"));
  ASSERT_EQ(doc["tracks"].size(), 2u);
  for (int t = 0; t < 2; ++t) {
    const double hz = doc["tracks"][t]["mean_natural_frequency"].get<double>() / (2.0 * M_PI);
    EXPECT_NEAR(hz, t == 0 ? 5.0 : 12.0, 0.05) << t;
    EXPECT_EQ(doc["tracks"][t]["windows_matched"], 3);
  }
  EXPECT_EQ(doc["options"]["oma"]["max_order"], 20);
  EXPECT_TRUE(std::filesystem::exists(path("tracking.csv")));
  testing::expect_bad_input(ctid({"track", data, "--output-only", "--output-columns", "a:c",
                                  "--window", "40", "--poles", "2"}),
                            "track", "--poles is not available with --output-only");
  testing::expect_bad_input(ctid({"track", data, "--output-only", "--output-columns", "a:c",
                                  "--window", "40", "--max-iterations", "5"}),
                            "track", "--max-iterations is not available with --output-only");
  testing::expect_bad_input(ctid({"track", data, "--output-only", "--window", "40"}), "track",
                            "--output-only needs --output-columns");
  testing::expect_bad_input(ctid({"track", data, "--output-only", "--output-columns", "a:c",
                                  "--window", "40", "--reference-columns", "d"}),
                            "track", "--reference-columns names 'd'");
}

// `ctid batch --output-only` (decision 0061): every record runs ctid oma with the spec's flags;
// a document is the bytes a single `ctid oma -o` writes, the summary has the modes, a record
// without a resonance is "no usable model" and a malformed one fails alone.
TEST_F(OmaCommand, BatchOutputOnlyRunsOmaOnEveryRecord) {
  std::filesystem::create_directories(path("records"));
  resonances("records/r1.csv", "c", -0.8, 0.6, 10);
  resonances("records/r2.csv", "c", 0.4, -1.1, 11);
  std::filesystem::rename(white_noise(), path("records/noise.csv"));
  write("records/bad.csv", "t,a,b,c\n0,1,2\n");
  write("spec.json", R"({"output-columns": "a:c", "max-order": 20, "block-rows": 20})");
  const auto r = ctid({"batch", "--output-only", "--glob", path("records/*.csv").string(), "--spec",
                       path("spec.json").string(), "-o", path("out").string(), "-j", "2", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json summary = io::read_json(path("out/summary.json"));
  std::map<std::string, nlohmann::json> rows;
  for (const nlohmann::json& row : summary["records"]) rows[row["name"]] = row;
  ASSERT_EQ(rows.size(), 4u) << summary.dump();
  for (const char* name : {"r1", "r2"}) {
    const nlohmann::json& row = rows[name];
    EXPECT_EQ(row["status"], "ok") << row.dump();
    EXPECT_EQ(row["estimator"], "ssi-cov");
    ASSERT_EQ(row["modes"].size(), 2u) << row.dump();
    for (int m = 0; m < 2; ++m) {
      const nlohmann::json& mode = row["modes"][m];
      EXPECT_NEAR(mode["frequency_hz"].get<double>(), m == 0 ? 5.0 : 12.0, 0.05) << name;
      EXPECT_NEAR(mode["damping"].get<double>(), 0.02, 0.01) << name;
      EXPECT_GT(mode["frequency_se_hz"].get<double>(), 0.0) << name;
      EXPECT_GT(mode["damping_se"].get<double>(), 0.0) << name;
    }
  }
  EXPECT_EQ(rows["noise"]["status"], "no_usable_model");
  EXPECT_THAT(rows["noise"]["message"].get<std::string>(), HasSubstr("no mode found"));
  EXPECT_EQ(rows["bad"]["status"], "failed");
  EXPECT_THAT(rows["bad"]["message"].get<std::string>(), HasSubstr("ctid oma: error: "));
  const auto single = ctid({"oma", path("records/r1.csv").string(), "--output-columns", "a:c",
                            "--max-order", "20", "--block-rows", "20", "-o", "single.json", "-q"});
  ASSERT_EQ(single.status, 0) << single.err;
  EXPECT_TRUE(io::read_text_file(path("out/r1.json").string()) ==
              io::read_text_file(path("single.json").string()))
      << "out/r1.json differs from the single ctid oma document";
  // The plan names ctid oma; a fit flag in the spec is refused before anything runs.
  const auto plan = ctid({"batch", "--output-only", "--glob", path("records/r*.csv").string(),
                          "--spec", path("spec.json").string(), "-o", "planned", "--plan"});
  ASSERT_EQ(plan.status, 0) << plan.err;
  EXPECT_EQ(nlohmann::json::parse(plan.out)[0]["args"][0], "oma");
  write("fit_spec.json", R"({"output-columns": "a:c", "modes": 2})");
  testing::expect_bad_input(
      ctid({"batch", "--output-only", "--glob", path("records/r*.csv").string(), "--spec",
            path("fit_spec.json").string(), "-o", "refused"}),
      "batch", "field 'modes' is not a ctid oma flag");
}

TEST_F(OmaCommand, BadUsageNamesTheFlag) {
  const std::string noise = white_noise();
  auto r = ctid({"oma", noise, "--output-columns", "a"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("needs at least 2 (--output-columns)"));
  r = ctid({"oma", noise, "--output-columns", "a,b", "--reference-columns", "c"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("--reference-columns names 'c'"));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--rows", "0:10", "--time", "0:1"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("give --rows or --time, not both"));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--time", "100:200"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("noise.csv: "));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--method", "pp"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err,
              HasSubstr("--method is 'pp'; it must be ssi-cov, ssi-data, fdd, efdd or plscf"));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--method", "efdd", "--efdd-mac", "1.5"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("--efdd-mac is 1.5; it must be in (0, 1]"));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--method", "fdd", "--segment-length", "8"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("the segment length is 8 samples; it must lie within 16.."));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--max-order", "40", "--block-rows", "10"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("--max-order is 40; the Hankel matrix of 10 block rows"));
  r = ctid({"oma", noise, "--output-columns", "a:c", "--max-order", "700"});
  EXPECT_EQ(r.status, 2);
  EXPECT_THAT(r.err, HasSubstr("the record has 4000 samples"));
}

}  // namespace
}  // namespace ctid::cli::oma_test

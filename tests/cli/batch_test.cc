// `ctid batch` run as a user would: a handful of simulated records (one mode, two modes,
// unfactored, a detrend override) and corrupted files in JSON and CSV manifests and a glob.
// Each good document must be the bytes a single `ctid fit -o` writes, each bad record's
// message must reach the summary, a rerun must skip finished records, bad manifests exit 2
// with one line, and nothing the user wrote is replaced without --force.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"

namespace ctid::cli::batch_test {
namespace {

namespace fs = std::filesystem;
using testing::expect_bad_input;
using ::testing::HasSubstr;
using testing::slurp;

class BatchCommand : public testing::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    write("one.json",
          R"({"type":"additive_model","submodels":[{"denominator_ascending":[1.0,0.04,0.04],)"
          R"("numerator_ascending":[2.0]}],"input_delay":0.0})");
    write("two.json",
          R"({"type":"additive_model","submodels":[{"denominator_ascending":[1.0,0.04,0.04],)"
          R"("numerator_ascending":[2.0]},{"denominator_ascending":[1.0,0.01,0.0025],)"
          R"("numerator_ascending":[1.0]}],"input_delay":0.0})");
    fs::create_directories(path("records"));
    simulate("one.json", "records/a1.csv", 1);
    simulate("one.json", "records/a2.csv", 2);
    simulate("two.json", "records/b1.csv", 3);
    simulate("two.json", "records/b2.csv", 4);
    // Corrupted records: a NaN, a missing column, a truncated file, not a CSV at all.
    write("records/nan.csv", "t,u,y\n0,1,0\n0.01,1,nan\n0.02,1,0.5\n");
    write("records/nocolumn.csv", "t,u,z\n0,1,0\n0.01,1,0.2\n0.02,1,0.5\n");
    write("records/truncated.csv", slurp(path("records/a1.csv")).substr(0, 200));
    write("records/binary.csv", std::string("\x89PNG\r\n\x1a\n\x00\x01\x02", 11));
  }

  void simulate(const std::string& model, const std::string& out, int seed) const {
    const auto r = ctid({"simulate", "-m", model, "-e", "prbs", "-n", "600", "-T", "0.01", "--seed",
                         std::to_string(seed), "--snr", "30", "--noise-seed", std::to_string(seed),
                         "-o", out, "-q"});
    ASSERT_EQ(r.status, 0) << r.err;
  }

  // The JSON manifest of the first test: shared spec, overrides, four corrupted records.
  std::string json_manifest() const {
    write("records/manifest.json", R"({
      "spec": {"modes": 1, "start": "auto"},
      "records": [
        {"data": "a1.csv"},
        {"name": "a2-linear", "data": "a2.csv", "detrend": "linear"},
        {"data": "b1.csv", "modes": 2},
        {"name": "b2-unfactored", "data": "b2.csv", "modes": null, "poles": 4, "zeros": 2},
        {"data": "nan.csv"}, {"data": "nocolumn.csv"}, {"data": "truncated.csv"},
        {"data": "binary.csv"}
      ]})");
    return "records/manifest.json";  // relative: the documents name the data as the fit does
  }

  // Expects OUT/<name>.json to be the bytes of `ctid fit DATA FLAGS -o single/<name>.json`.
  void expect_single_fit(const std::string& out, const std::string& name,
                         std::vector<std::string> fit_args) const {
    fs::create_directories(path("single"));
    const std::string single = "single/" + name + ".json";
    fit_args.insert(fit_args.begin(), "fit");
    fit_args.insert(fit_args.end(), {"-o", single, "-q"});
    const auto r = ctid(fit_args);
    ASSERT_TRUE(r.status == 0 || r.status == 3) << r.err;
    // Compared as text, reported as a line: a document is a few hundred lines.
    const std::string batch = slurp(path(out + "/" + name + ".json"));
    EXPECT_FALSE(batch.empty()) << name;
    EXPECT_TRUE(batch == slurp(path(single)))
        << out << "/" << name << ".json differs from " << single;
  }

  // The summary rows by name: column name -> cell.
  std::map<std::string, std::map<std::string, std::string>> summary(const std::string& out) const {
    const nlohmann::json document = io::read_json(path(out + "/summary.json"));
    std::map<std::string, std::map<std::string, std::string>> rows;
    for (const nlohmann::json& row : document["records"]) {
      auto& cells = rows[row["name"].get<std::string>()];
      for (const auto& [key, value] : row.items()) {
        cells[key] = value.is_string() ? value.get<std::string>() : value.dump();
      }
    }
    return rows;
  }
};

TEST_F(BatchCommand, JsonManifestRunsEveryRecordAndIsolatesFailures) {
  const auto r = ctid({"batch", json_manifest(), "--out", "out", "--jobs", "2"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, "ctid batch: 4 ok, 0 no usable model, 4 failed; summary in out/summary.csv\n");

  expect_single_fit("out", "a1", {"records/a1.csv", "--modes", "1"});
  expect_single_fit("out", "a2-linear", {"records/a2.csv", "--modes", "1", "--detrend", "linear"});
  expect_single_fit("out", "b1", {"records/b1.csv", "--modes", "2"});
  expect_single_fit("out", "b2-unfactored", {"records/b2.csv", "--poles", "4", "--zeros", "2"});

  const auto rows = summary("out");
  ASSERT_EQ(rows.size(), 8u);
  EXPECT_EQ(rows.at("a1").at("status"), "ok");
  EXPECT_EQ(rows.at("b2-unfactored").at("estimator"), "srivc");
  EXPECT_THAT(rows.at("nan").at("message"), HasSubstr("is not finite"));
  EXPECT_THAT(rows.at("nocolumn").at("message"), HasSubstr("no column 'y'"));
  EXPECT_THAT(rows.at("truncated").at("message"), HasSubstr("ctid fit: error: "));
  EXPECT_THAT(rows.at("binary").at("message"), HasSubstr("ctid fit: error: "));
  for (const char* bad : {"nan", "nocolumn", "truncated", "binary"}) {
    EXPECT_EQ(rows.at(bad).at("status"), "failed") << bad;
    const nlohmann::json error = io::read_json(path(std::string("out/") + bad + ".error.json"));
    EXPECT_EQ(error["record"], bad);
    EXPECT_EQ(error["exit_status"], 2) << bad;
    EXPECT_FALSE(fs::exists(path(std::string("out/") + bad + ".json"))) << bad;
  }

  // The CSV: manifest order, two modes' columns (b1), the message of a failed record.
  const std::string csv = slurp(path("out/summary.csv"));
  EXPECT_THAT(csv, ::testing::StartsWith(
                       "name,data,status,usable,fit_percent,estimator,mode1_frequency_hz,"
                       "mode1_frequency_se_hz,mode1_damping,mode1_damping_se,mode2_frequency_hz,"
                       "mode2_frequency_se_hz,mode2_damping,mode2_damping_se,seconds,message\n"
                       "a1,records/a1.csv,ok,true,"));
  EXPECT_THAT(csv, HasSubstr("\nnan,records/nan.csv,failed,,,,"));
  // The second mode of b1 (1 / sqrt(0.0025) = 20 rad/s, 3.18 Hz), in summary.json.
  const nlohmann::json b1 = io::read_json(path("out/summary.json"))["records"][2];
  ASSERT_EQ(b1["modes"].size(), 2u);
  EXPECT_NEAR(b1["modes"][1]["frequency_hz"].get<double>(), 20.0 / (2.0 * M_PI), 0.02);
  EXPECT_GT(b1["modes"][1]["frequency_se_hz"].get<double>(), 0.0);

  // --strict: a failed record makes the exit status 1 (nothing is run again).
  EXPECT_EQ(ctid({"batch", "records/manifest.json", "--out", "out", "--strict", "-q"}).status, 1);
}

TEST_F(BatchCommand, CsvManifestAndGlobGiveTheSingleFits) {
  write("records/manifest.csv",
        "name,data,modes,detrend\n"
        "first,a1.csv,1,\n"
        "second,b1.csv,2,linear\n");
  auto r = ctid({"batch", "records/manifest.csv", "--out", "csv", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, "");
  expect_single_fit("csv", "first", {"records/a1.csv", "--modes", "1"});
  expect_single_fit("csv", "second", {"records/b1.csv", "--modes", "2", "--detrend", "linear"});

  write("spec.json", R"({"modes": 1, "history": true})");
  r = ctid({"batch", "--glob", "records/a*.csv", "--spec", "spec.json", "--out", "glob"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("2 ok, 0 no usable model, 0 failed"));
  expect_single_fit("glob", "a1", {"records/a1.csv", "--modes", "1", "--history"});
  expect_single_fit("glob", "a2", {"records/a2.csv", "--modes", "1", "--history"});
}

TEST_F(BatchCommand, RerunSkipsFinishedRecordsAndRetriesFailedOnRequest) {
  ASSERT_EQ(ctid({"batch", json_manifest(), "--out", "out", "-q"}).status, 0);
  std::map<std::string, fs::file_time_type> before;
  for (const auto& entry : fs::directory_iterator(path("out"))) {
    before[entry.path().filename().string()] = fs::last_write_time(entry.path());
  }
  fs::remove(path("out/b1.json"));
  // Past the file system's time resolution, so a rewritten document would show.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  const auto r = ctid({"batch", "records/manifest.json", "--out", "out"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("4 ok, 0 no usable model, 4 failed"));
  for (const auto& [name, time] : before) {
    if (name.starts_with("summary") || name == "timings.json" || name == "b1.json") continue;
    EXPECT_EQ(fs::last_write_time(path("out/" + name)), time) << name << " was written again";
  }
  expect_single_fit("out", "b1", {"records/b1.csv", "--modes", "2"});

  // The NaN record repaired: a plain rerun still skips it, --retry-failed fits it.
  write("records/nan.csv", slurp(path("records/a1.csv")));
  ASSERT_EQ(ctid({"batch", "records/manifest.json", "--out", "out", "-q"}).status, 0);
  EXPECT_TRUE(fs::exists(path("out/nan.error.json")));
  ASSERT_EQ(ctid({"batch", "records/manifest.json", "--out", "out", "--retry-failed"}).status, 0);
  EXPECT_FALSE(fs::exists(path("out/nan.error.json")));
  EXPECT_EQ(summary("out").at("nan").at("status"), "ok");
}

TEST_F(BatchCommand, PlanListsTheFitCommandsAndRunsNothing) {
  const auto r = ctid({"batch", json_manifest(), "--out", "out", "--plan"});
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json plan = nlohmann::json::parse(r.out);
  ASSERT_EQ(plan.size(), 8u);
  EXPECT_EQ(plan[1]["name"], "a2-linear");
  // Records run side by side: each fit on one thread (decision 0068).
  EXPECT_EQ(plan[1]["args"], nlohmann::json({"fit", "records/a2.csv", "--detrend=linear",
                                             "--modes=1", "--start=auto", "--threads=1", "--output",
                                             "out/a2-linear.json", "--quiet"}));
  EXPECT_EQ(plan[1]["done"], false);
  EXPECT_FALSE(fs::exists(path("out")));
}

// A flag that is on by default (fit's --compute-covariance) is turned off by false in a spec
// and by "false" in a CSV cell: the documents are those of `ctid fit --compute-covariance=false`.
TEST_F(BatchCommand, FalseTurnsOffAFlagThatIsOnByDefault) {
  write("spec.json", R"({"modes": 1, "compute-covariance": false})");
  auto r =
      ctid({"batch", "--glob", "records/a1.csv", "--spec", "spec.json", "--out", "json", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  expect_single_fit("json", "a1", {"records/a1.csv", "--modes=1", "--compute-covariance=false"});
  EXPECT_TRUE(io::read_json(path("json/a1.json").string())["standard_errors"].empty());
  write("m.csv", "name,data,modes,compute-covariance\na1,records/a1.csv,1,no\n");
  r = ctid({"batch", "m.csv", "--out", "csv", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(path("csv/a1.json")), slurp(path("json/a1.json")));
}

TEST_F(BatchCommand, BadManifestsExitTwoWithOneLine) {
  write("broken.json", R"({"records": [{"data": "records/a1.csv"},)");
  expect_bad_input(ctid({"batch", "broken.json", "--out", "out"}), "batch", "broken.json");

  write("typo.json", R"({"spec": {"mdoes": 1}, "records": [{"data": "records/a1.csv"}]})");
  auto r = ctid({"batch", "typo.json", "--out", "out"});
  expect_bad_input(r, "batch", "field 'mdoes' is not a ctid fit flag");
  EXPECT_THAT(r.err, HasSubstr("did you mean 'modes'?"));
  // A flag renamed by decision 0055 is named with its new spelling, in the manifest's words.
  write("renamed.json", R"({"spec": {"delay": 1}, "records": [{"data": "records/a1.csv"}]})");
  r = ctid({"batch", "renamed.json", "--out", "out"});
  expect_bad_input(r, "batch", "field 'delay' is not a ctid fit flag");
  EXPECT_THAT(r.err, HasSubstr("delay is now input-delay-samples, a count of samples"));

  // Names the user wrote must differ (a name derived from a path steps aside instead).
  write("twice.json", R"({"spec": {"modes": 1}, "records": [{"data": "records/a1.csv", )"
                      R"("name": "a1"}, {"data": "records/a2.csv", "name": "a1"}]})");
  expect_bad_input(ctid({"batch", "twice.json", "--out", "out"}), "batch",
                   "twice.json: record 2 ('a1'): the name 'a1' is taken by twice.json: record 1");

  write("nodata.json", R"({"spec": {"modes": 1}, "records": [{"name": "x"}]})");
  expect_bad_input(ctid({"batch", "nodata.json", "--out", "out"}), "batch",
                   "nodata.json: record 1 ('x'): field 'data' is missing");

  write("output.json", R"({"records": [{"data": "records/a1.csv", "output": "x.json"}]})");
  expect_bad_input(ctid({"batch", "output.json", "--out", "out"}), "batch",
                   "field 'output' cannot be set in a batch");

  write("value.json", R"({"spec": {"modes": "two"}, "records": [{"data": "records/a1.csv"}]})");
  r = ctid({"batch", "value.json", "--out", "out"});
  expect_bad_input(r, "batch", "value.json: record 1: the flags are not valid for ctid fit: ");
  EXPECT_THAT(r.err, HasSubstr("--modes"));

  write("nodata.csv", "name,modes\nx,1\n");
  expect_bad_input(ctid({"batch", "nodata.csv", "--out", "out"}), "batch",
                   "nodata.csv: column 'data' is missing");
  EXPECT_FALSE(fs::exists(path("out")));
}

TEST_F(BatchCommand, NothingTheUserWroteIsReplacedWithoutForce) {
  fs::create_directories(path("out"));
  write("out/summary.csv", "my own notes\n");
  expect_bad_input(ctid({"batch", json_manifest(), "--out", "out"}), "batch",
                   "out/summary.csv: file exists and is not a ctid batch summary; pass --force");
  EXPECT_EQ(slurp(path("out/summary.csv")), "my own notes\n");
  EXPECT_FALSE(fs::exists(path("out/a1.json")));

  write("file-not-folder", "x");
  expect_bad_input(ctid({"batch", "records/manifest.json", "--out", "file-not-folder"}), "batch",
                   "exists and is not a directory");
  EXPECT_EQ(slurp(path("file-not-folder")), "x");

  const auto r = ctid({"batch", "records/manifest.json", "--out", "out", "--force", "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(slurp(path("out/summary.csv")), ::testing::StartsWith("name,data,status,"));
}

// Issue 33, finding 1: `ctid batch o/m.json -o o --force` once wrote record m's result over
// the manifest. An output that is an input is refused before any work, --force or not.
TEST_F(BatchCommand, NoOutputIsTheManifestTheSpecOrAData) {
  const auto refused = [&](const std::vector<std::string>& args,
                           const std::vector<std::string>& fragments) {
    const auto r = ctid(args);
    expect_bad_input(r, "batch", "--force does not change this");
    for (const std::string& fragment : fragments) EXPECT_THAT(r.err, HasSubstr(fragment));
  };
  fs::create_directories(path("o"));
  write("o/m.json", R"({"spec":{"modes":1},"records":[{"name":"m","data":"../records/a1.csv"}]})");
  const std::string manifest = slurp(path("o/m.json"));
  refused({"batch", "o/m.json", "-o", "o", "--force"}, {"'o/m.json' is the manifest 'o/m.json'"});
  EXPECT_EQ(slurp(path("o/m.json")), manifest);
  EXPECT_FALSE(fs::exists(path("o/summary.csv")));
  // The spec, reached through a link in the output folder, and a data file that would be
  // its own record's result: both refused, and neither changed.
  write("spec.json", R"({"modes": 1})");
  fs::create_directories(path("p"));
  fs::create_symlink("../spec.json", path("p/a1.json"));
  refused({"batch", "--glob", "records/a1.csv", "--spec", "spec.json", "-o", "p"},
          {"'p/a1.json' is the spec 'spec.json'"});
  EXPECT_EQ(slurp(path("spec.json")), R"({"modes": 1})");
  fs::create_directories(path("q"));
  write("q/x.json", slurp(path("records/a1.csv")));
  const std::string data = slurp(path("q/x.json"));
  refused({"batch", "--glob", "q/x.json", "--spec", "spec.json", "-o", "q", "--force"},
          {"the result 'q/x.json' is", "the file 'q/x.json'"});
  EXPECT_EQ(slurp(path("q/x.json")), data);
}

// Issue 33, finding 5: names derived from paths are unique and safe by construction, so a
// --glob batch of site_a/rec.csv, site_b/rec.csv and "rec 2.csv" runs every record.
TEST_F(BatchCommand, GlobNamesAreUniqueAndSafe) {
  for (const char* folder : {"g/siteA", "g/siteB"}) fs::create_directories(path(folder));
  write("g/siteA/rec.csv", slurp(path("records/a1.csv")));
  write("g/siteB/rec.csv", slurp(path("records/a2.csv")));
  write("g/siteA/rec 2.csv", slurp(path("records/a1.csv")));
  write("spec.json", R"({"modes": 1})");
  const auto r = ctid({"batch", "--glob", "g/*/rec*.csv", "--spec", "spec.json", "-o", "out"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, "ctid batch: 3 ok, 0 no usable model, 0 failed; summary in out/summary.csv\n");
  const auto rows = summary("out");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows.at("siteA_rec").at("data"), "g/siteA/rec.csv");
  EXPECT_EQ(rows.at("siteB_rec").at("data"), "g/siteB/rec.csv");
  EXPECT_EQ(rows.at("rec_2").at("data"), "g/siteA/rec 2.csv");
  expect_single_fit("out", "siteB_rec", {"g/siteB/rec.csv", "--modes", "1"});
}

}  // namespace
}  // namespace ctid::cli::batch_test

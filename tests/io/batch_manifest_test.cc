#include "ctid/io/batch_manifest.h"

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/io/json.h"

namespace ctid::io::batch_manifest_test {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

BatchManifest from_json(const std::string& text, const ManifestKeyCheck& check = {}) {
  return batch_manifest_from_json(parse_json(text, "in/m.json"), "in/m.json", check);
}

std::string json_error(const std::string& text, const ManifestKeyCheck& check = {}) {
  try {
    (void)from_json(text, check);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(no error)";
}

std::string csv_error(const std::string& text) {
  try {
    (void)batch_manifest_from_csv(text, "in/m.csv");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(no error)";
}

std::string names_error(const std::vector<ManifestRecord>& records) {
  try {
    (void)record_names(records);
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "(no error)";
}

ManifestRecord record(const std::string& data, const std::string& name = "") {
  return {name, {data}, {}, "record of " + data};
}

TEST(BatchManifest, JsonRecordsTakeRelativePathsFromTheManifestsFolder) {
  const BatchManifest manifest = from_json(
      R"({"spec": {"modes": 1}, "records": [{"data": "a/r.csv"},
          {"name": "b", "data": ["/abs/b.csv", "-dash.csv"], "poles": 4}]})");
  EXPECT_EQ(manifest.spec.at("modes").value, 1);
  ASSERT_EQ(manifest.records.size(), 2U);
  EXPECT_THAT(manifest.records[0].data, ElementsAre("in/a/r.csv"));
  EXPECT_EQ(manifest.records[0].name, "");
  EXPECT_EQ(manifest.records[1].name, "b");
  EXPECT_THAT(manifest.records[1].data, ElementsAre("/abs/b.csv", "in/-dash.csv"));
  EXPECT_EQ(manifest.records[1].settings.at("poles").value, 4);
  EXPECT_FALSE(manifest.records[1].settings.at("poles").from_csv);
  EXPECT_EQ(manifest.records[1].context, "in/m.json: record 2 ('b')");
}

TEST(BatchManifest, APathThatWouldReadAsAFlagGetsDotSlash) {
  const BatchManifest manifest = batch_manifest_from_json(
      parse_json(R"({"records": [{"data": "-x.csv"}]})", "m.json"), "m.json");
  EXPECT_THAT(manifest.records[0].data, ElementsAre("./-x.csv"));
}

TEST(BatchManifest, CsvCellsAreQuotedAcrossLinesAndKeptAsText) {
  const BatchManifest manifest = batch_manifest_from_csv(
      "name,data,submodel\r\np,\"x \"\"q\"\",\n.csv\",\"2,0 2,1\"\r\n\r\nq,y.csv,\n", "in/m.csv");
  ASSERT_EQ(manifest.records.size(), 2U);
  EXPECT_THAT(manifest.records[0].data, ElementsAre("in/x \"q\",\n.csv"));
  EXPECT_EQ(manifest.records[0].settings.at("submodel").value, "2,0 2,1");
  EXPECT_TRUE(manifest.records[0].settings.at("submodel").from_csv);
  EXPECT_EQ(manifest.records[1].settings.count("submodel"), 0U);  // empty cell: not given
}

TEST(BatchManifest, MalformedManifestsNameWhatIsWrong) {
  EXPECT_THAT(json_error("[1]"), HasSubstr("in/m.json: a manifest is a JSON object"));
  EXPECT_THAT(json_error(R"({"records": [], "extra": 1})"),
              HasSubstr("field 'extra' is not a manifest field (spec, records)"));
  EXPECT_THAT(json_error(R"({"spec": 1, "records": []})"), HasSubstr("'spec' is a JSON object"));
  EXPECT_THAT(json_error(R"({"spec": {}})"), HasSubstr("field 'records' (a list of records)"));
  EXPECT_THAT(json_error(R"({"records": [{"name": 3, "data": "a"}]})"),
              HasSubstr("record 1: field 'name' is 3; it is a string"));
  EXPECT_THAT(json_error(R"({"records": [{"name": "a"}]})"),
              HasSubstr("record 1 ('a'): field 'data' is missing"));
  EXPECT_THAT(json_error(R"({"records": [{"data": ""}]})"),
              HasSubstr("field 'data' is \"\"; it is a file path or a list of them"));
  EXPECT_THAT(json_error(R"({"records": ["a.csv"]})"), HasSubstr("a record is a JSON object"));
  EXPECT_THAT(json_error(R"({"spec": {"data": "a"}, "records": []})"),
              HasSubstr("field 'data' belongs to a record, not to the shared spec"));
  EXPECT_THAT(csv_error(""), HasSubstr("in/m.csv: the manifest is empty"));
  EXPECT_THAT(csv_error("name\na\n"), HasSubstr("column 'data' is missing from the header"));
  EXPECT_THAT(csv_error("data,data\na,b\n"), HasSubstr("column 'data' is given twice"));
  EXPECT_THAT(csv_error("data,modes\na\n"), HasSubstr("record 1: 1 cells; the header has 2"));
  EXPECT_THAT(csv_error("data\n\"a\n"),
              HasSubstr("in/m.csv: line 2: the quote opened here is not closed"));
}

TEST(BatchManifest, EveryFlagNameGoesThroughTheCallersCheck) {
  std::vector<std::string> seen;
  const ManifestKeyCheck check = [&](const std::string& key, const std::string& context) {
    seen.push_back(context + " " + key);
    if (key == "bogus") throw InvalidArgument(context + ": '" + key + "' is not a flag");
  };
  (void)from_json(R"({"spec": {"modes": 1}, "records": [{"name": "r", "data": "a", "poles": 2}]})",
                  check);
  EXPECT_THAT(seen, ElementsAre("in/m.json: spec modes", "in/m.json: record 1 ('r') poles"));
  EXPECT_THAT(json_error(R"({"records": [{"data": "a", "bogus": 1}]})", check),
              HasSubstr("in/m.json: record 1: 'bogus' is not a flag"));
}

TEST(BatchManifest, DerivedNamesAreSafeAndUniqueByConstruction) {
  const std::vector<std::string> names =
      record_names({record("g/siteA/rec.csv"), record("g/siteB/rec.csv"), record("rec 2.csv"),
                    record("g/siteA_rec.csv"), record("x/summary.csv"), record(".h.csv"),
                    record("a.csv", "siteA_rec")});
  EXPECT_THAT(names, ElementsAre("siteA_rec-2", "siteB_rec", "rec_2", "siteA_rec-3",
                                 "summary_record", "_.h", "siteA_rec"));
  for (const std::string& name : names) EXPECT_NO_THROW(check_record_name(name, "derived"));
}

TEST(BatchManifest, StemsSharedAcrossRootsStillGetNames) {
  const std::vector<std::string> names =
      record_names({record("../../a/r.csv"), record("/r.csv"), record("r.csv")});
  ASSERT_EQ(names.size(), 3U);
  EXPECT_NE(names[0], names[1]);
  EXPECT_NE(names[1], names[2]);
  EXPECT_NE(names[0], names[2]);
  for (const std::string& name : names) EXPECT_NO_THROW(check_record_name(name, "derived"));
}

TEST(BatchManifest, GivenNamesThatAreNoFileNamesOrTakenTwiceAreRefused) {
  EXPECT_THAT(names_error({record("a.csv", "a/b")}),
              HasSubstr("record of a.csv: field 'name' is 'a/b'; a name holds only letters"));
  EXPECT_THAT(names_error({record("a.csv", ".a")}), HasSubstr("may not start with '.' or '-'"));
  EXPECT_THAT(names_error({record("a.csv", "x.error")}), HasSubstr("are the batch's own files"));
  EXPECT_THAT(names_error({record("a.csv", std::string(201, 'a'))}),
              HasSubstr("must have 1 to 200 characters"));
  EXPECT_THAT(names_error({record("a.csv", "n"), record("b.csv", "n")}),
              HasSubstr("record of b.csv: the name 'n' is taken by record of a.csv"));
}

}  // namespace
}  // namespace ctid::io::batch_manifest_test

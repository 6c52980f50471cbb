// `ctid structure` run as a user would: on the noise-free Section 6.1 record (four modes) a
// scan over three to five modes recommends four, prints its table and writes the scan; bad
// ranges exit 2 with one line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli/run_ctid.h"
#include "ctid/io/json.h"

namespace ctid::cli {
namespace {

using ::testing::HasSubstr;

class StructureCommand : public testing::Section61Test {};

void expect_bad_input(const testing::RunResult& r, const std::string& fragment) {
  testing::expect_bad_input(r, "structure", fragment);
}

TEST_F(StructureCommand, RecommendsTheTrueNumberOfModesAndWritesTheScan) {
  const auto r = ctid({"structure", "d.csv", "--modes", "3:5", "-o", "s.json"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("3 structures on d.csv (5735 samples fitted, 2457 held out)"));
  EXPECT_THAT(r.out, HasSubstr(" * 4 modes"));
  EXPECT_THAT(r.out, HasSubstr("recommended: 4 modes (fewest parameters"));
  const nlohmann::json j = io::read_json(path("s.json"));
  EXPECT_EQ(j.at("type"), "structure_scan_result");
  ASSERT_EQ(j.at("fits").size(), 3U);
  EXPECT_EQ(j.at("recommended"), 1);
  EXPECT_GT(j.at("fits")[1].at("validation_fit").get<double>(), 99.99);
  EXPECT_TRUE(j.at("fits")[1].at("usable").get<bool>());
  EXPECT_FALSE(j.at("stabilisation").empty());
}

TEST_F(StructureCommand, BadRangesExitTwoWithOneLine) {
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "3:1"}), "MAX is below MIN");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "x"}), "expected MIN:MAX");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "1:2", "--poles", "1:2"}),
                   "give one range");
  expect_bad_input(ctid({"structure", "d.csv", "--poles", "2:3", "--zeros", "5"}),
                   "an improper model");
  expect_bad_input(ctid({"structure", "d.csv", "--modes", "1:2", "--validation-fraction", "2"}),
                   "validation_fraction is 2");
}

}  // namespace
}  // namespace ctid::cli

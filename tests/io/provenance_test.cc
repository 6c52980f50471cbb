#include "ctid/io/provenance.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace ctid::io::provenance_test {
namespace {

using nlohmann::json;

TEST(Provenance, OnlyTheFieldsSetBecomeKeys) {
  EXPECT_EQ(to_json(DataProvenance{.files = {"a.csv"}}), json({{"file", "a.csv"}}));
  DataProvenance p;
  p.files = {"a.csv"};
  p.samples = 600;
  p.sample_time = 0.01;
  p.input_hold = Hold::first_order_hold;
  EXPECT_EQ(to_json(p), json({{"file", "a.csv"},
                              {"samples", 600},
                              {"sample_time", 0.01},
                              {"input_hold", "first_order_hold"}}));
}

TEST(Provenance, SeveralRecordsListEveryFileAndLength) {
  DataProvenance p;
  p.files = {"a.csv", "b.csv"};
  p.record_samples = {400, 500};
  const json block = to_json(p);
  EXPECT_EQ(block["file"], "a.csv");
  EXPECT_EQ(block["files"], json({"a.csv", "b.csv"}));
  EXPECT_EQ(block["record_samples"], json({400, 500}));
}

TEST(Provenance, IrregularStampsAreNamedWithTheirDuplicates) {
  DataProvenance p;
  p.files = {"log.csv"};
  p.duplicate_stamps = 3;
  p.detrend = "mean";
  const json block = to_json(p);
  EXPECT_EQ(block["time_stamps"], "irregular");
  EXPECT_EQ(block["duplicate_stamps"], 3);
  EXPECT_EQ(block["detrend"], "mean");
  EXPECT_FALSE(block.contains("preprocessing"));
}

TEST(Provenance, PreprocessingIsItsFieldList) {
  DataProvenance p;
  p.preprocessing = PreprocessingRecord{};
  p.preprocessing->decimate = 4;
  const json block = to_json(p);
  EXPECT_EQ(block["preprocessing"]["decimate"], 4);
  EXPECT_FALSE(block.contains("file"));
}

}  // namespace
}  // namespace ctid::io::provenance_test

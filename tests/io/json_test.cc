#include "ctid/io/json.h"

#include <filesystem>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "io/test_directory.h"

namespace ctid::io::json_test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string parse_error(const std::string& text) {
  try {
    parse_json(text, "m.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(Json, DeepNestingIsRefusedBeforeParsing) {
  // 140 000 nested arrays used to overflow the stack when the document was copied.
  const std::string deep = std::string(140000, '[') + std::string(140000, ']');
  EXPECT_EQ(parse_error(deep),
            "m.json:1:257: malformed JSON: arrays and objects nested deeper than 256 levels");
  // The same depth inside a string is text, and 256 levels are accepted.
  const std::string quoted = "{\"d\": \"" + std::string(1000, '[') + "\\\"[\"}";
  EXPECT_EQ(parse_error(quoted), "");
  const std::string deepest = std::string(256, '[') + std::string(256, ']');
  EXPECT_EQ(parse_error(deepest), "");
  EXPECT_EQ(parse_error("{\"a\":\n" + std::string(300, '{')),
            "m.json:2:256: malformed JSON: arrays and objects nested deeper than 256 levels");
}

TEST(Json, AKeyGivenTwiceInOneObjectIsRefused) {
  // nlohmann keeps the last of two equal keys silently; a model file with "inputs" twice is a
  // mistake to report, not a choice to make.
  EXPECT_EQ(parse_error("{\"type\": \"a\", \"inputs\": 2, \"inputs\": 3}"),
            "m.json: malformed JSON: the key \"inputs\" appears twice in one object");
  EXPECT_EQ(parse_error("{\"s\": [{\"b\": 1}, {\"b\": 2, \"c\": {\"b\": 3}}], \"b\": 4}"), "");
  EXPECT_THAT(parse_error("{\"s\": [{\"b\": 1, \"c\": 2, \"b\": 3}]}"),
              HasSubstr("the key \"b\" appears twice"));
}

TEST(Json, SyntaxErrorsNameFileLineAndColumn) {
  EXPECT_THAT(parse_error("{\n  \"a\": 1,\n  \"b\": NaN\n}\n"),
              StartsWith("m.json:3:8: malformed JSON"));
  EXPECT_THAT(parse_error("{\n  \"a\": [1, 2,]\n}"), StartsWith("m.json:2:14: malformed JSON"));
  EXPECT_THAT(parse_error("{\"a\": 1"), StartsWith("m.json:1:"));
  EXPECT_THAT(parse_error(""), StartsWith("m.json:1:"));
  EXPECT_THAT(parse_error("{\n\"a\": 1}\n}"), StartsWith("m.json:3:1: malformed JSON"));
}

TEST(Json, LocationAgreesWithTheParsersOwnReport) {
  // nlohmann's message carries "line L, column C"; ours must agree with it.
  const std::string text = "{\n  \"x\": [1,\n    2 3]\n}";
  try {
    const nlohmann::json parsed = nlohmann::json::parse(text);
    ADD_FAILURE() << parsed.dump();

  } catch (const nlohmann::json::parse_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("line 3, column 7"));
  }
  EXPECT_THAT(parse_error(text), StartsWith("m.json:3:7:"));
}

TEST(JsonObject, ReadsFieldsAndRejectsUnknownOnes) {
  const JsonObject o(
      nlohmann::json::parse(R"({"x": 1.5, "n": 3, "s": "hi", "v": [1, 2], "typo": 0})"), "m.json");
  EXPECT_EQ(o.number("x"), 1.5);
  EXPECT_EQ(o.integer("n"), 3);
  EXPECT_EQ(o.string("s"), "hi");
  EXPECT_EQ(o.numbers("v"), Eigen::Vector2d(1, 2));
  EXPECT_EQ(o.number_or("missing", 7.0), 7.0);
  try {
    o.finish();
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), StartsWith("m.json: typo: unknown field (known fields here: "));
    EXPECT_THAT(e.what(), HasSubstr("missing, n, s, v, x"));
  }
}

TEST(JsonObject, TypeErrorsNameThePath) {
  const nlohmann::json doc = nlohmann::json::parse(R"({"a": {"v": [1, "2"], "n": 1.5, "w": 3}})");
  const JsonObject root(doc, "m.json");
  const JsonObject a = root.object("a");
  EXPECT_EQ(a.path(), "a");
  try {
    a.numbers("v");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "m.json: a.v[1]: expected a number but found a string");
  }
  try {
    a.integer("n");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "m.json: a.n: expected an integer but found 1.5");
  }
  try {
    a.string("w");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "m.json: a.w: expected a string but found a number");
  }
  try {
    a.number("absent");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "m.json: a.absent: required field is missing");
  }
  EXPECT_THROW(JsonObject(nlohmann::json::array(), "m.json"), InvalidArgument);
}

TEST(Json, OverflowingNumbersAreMalformedWithTheirLine) {
  // JSON has no NaN or infinity; a literal beyond the range of a double is located too.
  EXPECT_THAT(parse_error("{\n  \"v\": [1,\n  1e999]}"),
              StartsWith("m.json:3:3: malformed JSON: number overflow parsing '1e999'"));
}

TEST(JsonObject, NonFiniteNumbersBuiltInCodeAreRejected) {
  nlohmann::json doc;
  doc["v"] = {1.0, std::numeric_limits<double>::infinity()};
  doc["x"] = std::numeric_limits<double>::quiet_NaN();
  const JsonObject o(doc, "m.json");
  try {
    o.numbers("v");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "m.json: v[1]: value is not finite");
  }
  EXPECT_THROW(o.number("x"), InvalidArgument);
}

// Issue 33: a document larger than kMaxJsonDocumentBytes is refused from its size, before it is
// read (a sparse file: nothing is written to the disk).
TEST(Json, ADocumentOverSixtyFourMebibytesIsRefusedBeforeReading) {
  const testing::TestDirectory dir;
  const std::filesystem::path big = dir / "big.json";
  write_text_file(big, "{}", Overwrite::no);
  std::filesystem::resize_file(big, kMaxJsonDocumentBytes + 1);
  EXPECT_THAT([&] { read_json(big); },
              ::testing::ThrowsMessage<InvalidArgument>(::testing::HasSubstr(
                  "big.json: 64 MiB; ctid reads JSON documents (models, controllers, specs, "
                  "results) of at most 64 MiB")));
  std::filesystem::resize_file(big, 2);
  EXPECT_TRUE(read_json(big).is_object());
}

// Decision 0042: a file name is any bytes; what is not UTF-8 is written \xHH, as Python's
// "backslashreplace" writes it, and UTF-8 (up to four-byte characters) is kept as it is.
TEST(Json, BytesThatAreNotUtf8AreEscapedAndUtf8IsKept) {
  EXPECT_EQ(escape_invalid_utf8("caf\xc3\xa9 \xf0\x9f\x93\x88.csv"),
            "caf\xc3\xa9 \xf0\x9f\x93\x88.csv");
  EXPECT_EQ(escape_invalid_utf8("caf\xe9.csv"), "caf\\xe9.csv");
  EXPECT_EQ(escape_invalid_utf8("\xff\xfe"), "\\xff\\xfe");
  EXPECT_EQ(escape_invalid_utf8("\xc0\xaf"), "\\xc0\\xaf");                    // overlong '/'
  EXPECT_EQ(escape_invalid_utf8("\xed\xa0\x80"), "\\xed\\xa0\\x80");           // a surrogate
  EXPECT_EQ(escape_invalid_utf8("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // > U+10FFFF
  EXPECT_EQ(escape_invalid_utf8("a\xc3"), "a\\xc3");  // a character cut at the end
}

TEST(Json, ADocumentHoldingANameThatIsNotUtf8IsWrittenEscaped) {
  nlohmann::json document = {{"data", {{"file", "caf\xe9.csv"}}},
                             {"r\xe9sultats", {1.5, "na\xefve"}}};
  EXPECT_THROW((void)document.dump(), nlohmann::json::type_error);  // what used to happen
  const std::string text = json_text(document);
  const nlohmann::json back = parse_json(text, "back.json");
  EXPECT_EQ(back["data"]["file"], "caf\\xe9.csv");
  EXPECT_EQ(back["r\\xe9sultats"][1], "na\\xefve");
  EXPECT_EQ(back["r\\xe9sultats"][0], 1.5);
  const nlohmann::json plain = {{"file", "caf\xc3\xa9.csv"}, {"x", 0.1}};
  EXPECT_EQ(json_text(plain), plain.dump(2));
  EXPECT_EQ(json_text(plain, -1), plain.dump());
}

}  // namespace
}  // namespace ctid::io::json_test

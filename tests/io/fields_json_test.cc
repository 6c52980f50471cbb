#include "ctid/io/fields_json.h"

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ctid/core/error.h"
#include "ctid/core/fields.h"
#include "ctid/io/model_json.h"
#include "ctid/refined_iv/refined_iv_options.h"

namespace ctid::fields_json_test {
namespace {

using ::testing::HasSubstr;

// A nested pair of structs with every kind of field the mechanism supports.
enum class Colour { red, green };
inline constexpr std::array<Enumerator<Colour>, 2> colour_enumerators{{
    {Colour::red, "red", "Red."},
    {Colour::green, "green", "Green."},
}};
constexpr std::span<const Enumerator<Colour>> enumerators(Colour) { return colour_enumerators; }

struct InnerOptions {
  int substeps = 4;
  std::vector<double> poles{0.5, 1.0};
  static constexpr std::string_view type_name = "InnerOptions";
  static constexpr auto fields() {
    return std::tuple{field("substeps", &InnerOptions::substeps, AtLeast{1}, "Steps."),
                      field("poles", &InnerOptions::poles, Each{GreaterThan{0}}, "Poles.")};
  }
  void validate() const { validate_fields(*this); }
};

struct OuterOptions {
  double tolerance = 1e-10;
  Colour colour = Colour::green;
  std::optional<double> limit;
  InnerOptions inner;
  bool flag = true;
  std::string label = "x";
  static constexpr std::string_view type_name = "OuterOptions";
  static constexpr auto fields() {
    using O = OuterOptions;
    return std::tuple{field("tolerance", &O::tolerance, Between{0.0, 1.0}, "Tolerance."),
                      field("colour", &O::colour, "Colour."),
                      field("limit", &O::limit, AtLeast{2}, "Optional limit."),
                      field("inner", &O::inner, "Nested."),
                      field("flag", &O::flag, "Flag."),
                      field("label", &O::label, "Label.")};
  }
  void check_relations(const std::string& path) const {
    require(!(limit && *limit > 10 && !flag), path, ".limit above 10 needs flag");
  }
  void validate() const { validate_fields(*this); }
};

std::string validation_error(const OuterOptions& o) {
  try {
    o.validate();
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

template <class Change>
std::string error_after(Change change) {
  OuterOptions o;
  change(o);
  return validation_error(o);
}

TEST(Fields, ValidationNamesTheFullPathTheValueAndTheRule) {
  const OuterOptions defaults;
  EXPECT_EQ(validation_error(defaults), "");
  EXPECT_EQ(error_after([](OuterOptions& o) { o.inner.substeps = 0; }),
            "OuterOptions.inner.substeps is 0; it must be >= 1");
  EXPECT_EQ(error_after([](OuterOptions& o) {
              o.inner.poles = {1.0, 2.0, -1.0};
            }),
            "OuterOptions.inner.poles[2] is -1; it must be > 0");
  EXPECT_EQ(error_after([](OuterOptions& o) { o.tolerance = 1.0; }),
            "OuterOptions.tolerance is 1; it must be in (0, 1)");
  EXPECT_EQ(
      error_after([](OuterOptions& o) { o.tolerance = std::numeric_limits<double>::quiet_NaN(); }),
      "OuterOptions.tolerance is NaN; it must be a number");
  EXPECT_EQ(error_after([](OuterOptions& o) { o.limit = 1.5; }),
            "OuterOptions.limit is 1.5; it must be >= 2");
  EXPECT_EQ(error_after([](OuterOptions& o) {
              o.limit = 11;
              o.flag = false;
            }),
            "OuterOptions.limit above 10 needs flag");
  EXPECT_EQ(error_after([](OuterOptions& o) { o.colour = static_cast<Colour>(7); }),
            "OuterOptions.colour is 7; it must be one of red or green");
}

TEST(Fields, NamesAndEnumerators) {
  EXPECT_EQ(field_names<InnerOptions>(), (std::vector<std::string>{"substeps", "poles"}));
  EXPECT_EQ(enum_name(Colour::green), "green");
  EXPECT_EQ(enum_from_name<Colour>("red"), Colour::red);
  EXPECT_FALSE(enum_from_name<Colour>("blue").has_value());
  EXPECT_EQ(enum_names<Hold>(), "zero_order_hold or first_order_hold");
}

TEST(FieldsJson, RoundTripIsExactAndMissingKeysKeepDefaults) {
  OuterOptions o;
  o.tolerance = 0.1 + 0.2;  // not a short decimal
  o.colour = Colour::red;
  o.limit = 3.0;
  o.inner.poles = {1.0 / 3.0};
  o.label = "y";
  const nlohmann::json j = io::fields_to_json(o);
  EXPECT_EQ(j.at("colour"), "red");
  EXPECT_EQ(j.at("inner").at("substeps"), 4);
  const auto back = io::options_from_json<OuterOptions>(nlohmann::json::parse(j.dump()), "o.json");
  EXPECT_EQ(back.tolerance, o.tolerance);
  EXPECT_EQ(back.colour, o.colour);
  EXPECT_EQ(back.limit, o.limit);
  EXPECT_EQ(back.inner.poles, o.inner.poles);
  EXPECT_EQ(back.label, "y");
  const auto defaults = io::options_from_json<OuterOptions>(nlohmann::json::object(), "o.json");
  const OuterOptions reference;
  EXPECT_EQ(defaults.inner.poles, reference.inner.poles);
  EXPECT_FALSE(defaults.limit.has_value());
}

std::string read_error(const std::string& text) {
  try {
    io::options_from_json<OuterOptions>(nlohmann::json::parse(text), "o.json");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

TEST(FieldsJson, BadDocumentsNameSourcePathAndProblem) {
  EXPECT_EQ(read_error(R"({"tolerence": 1e-3})"),
            "o.json: OuterOptions: unknown field 'tolerence'; the fields of OuterOptions are "
            "tolerance, colour, limit, inner, flag, label");
  EXPECT_EQ(read_error(R"({"inner": {"substeps": "four"}})"),
            "o.json: OuterOptions.inner.substeps: expected an integer, got string");
  EXPECT_EQ(read_error(R"({"colour": "blue"})"),
            "o.json: OuterOptions.colour: 'blue' is not one of red or green");
  EXPECT_EQ(read_error(R"({"inner": {"substeps": 0}})"),
            "o.json: OuterOptions.inner.substeps is 0; it must be >= 1");
  EXPECT_EQ(read_error(R"({"inner": {"substeps": 1e10}})"),
            "o.json: OuterOptions.inner.substeps: expected an integer, got number");
  EXPECT_EQ(read_error(R"([1])"), "o.json: OuterOptions: expected an object, got array");
}

TEST(FieldsJson, RefinedIvOptionsRoundTripWithAStartingModel) {
  RefinedIvOptions o;
  o.max_iterations = 7;
  o.noise = NoiseAssumption::white;
  o.output_interpolation = Hold::zero_order_hold;
  o.initial_model = AdditiveModel({Submodel{Polynomial{1.0, 0.25, 0.5}, Polynomial{2.0}, 0}});
  const nlohmann::json j = io::fields_to_json(o);
  EXPECT_EQ(j.at("noise"), "white");
  EXPECT_EQ(j.at("output_interpolation"), "zero_order_hold");
  EXPECT_EQ(j.at("initial_model").at("type"), "additive_model");
  const auto back = io::options_from_json<RefinedIvOptions>(j, "r.json");
  EXPECT_EQ(back.max_iterations, 7);
  EXPECT_EQ(back.noise, NoiseAssumption::white);
  EXPECT_EQ(back.output_interpolation, Hold::zero_order_hold);
  ASSERT_TRUE(back.initial_model.has_value());
  EXPECT_EQ(back.initial_model->size(), 1);
  EXPECT_EQ((*back.initial_model)[0].a.coefficients(),
            o.initial_model->operator[](0).a.coefficients());
  EXPECT_THAT(read_error(R"({"tolerance": 2})"), HasSubstr("it must be in (0, 1)"));
}

}  // namespace
}  // namespace ctid::fields_json_test

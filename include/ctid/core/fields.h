// Fields listed once. An options or result struct names each of its fields in one static
// function `fields()`, with the rule its value must follow and one line of documentation, and
// gives its own name in `type_name`; validation (here), the JSON reader and writer
// (io/fields_json.h), the Python attributes, keywords and repr (python/src/fields.h) and the
// documentation tables are all derived from that list, so they cannot drift apart.
//
//   struct ExampleOptions {
//     int max_iterations = 100;
//     std::vector<double> poles{0.5};
//     Hold hold = Hold::first_order_hold;
//     static constexpr std::string_view type_name = "ExampleOptions";
//     static constexpr auto fields() {
//       return std::tuple{
//           field("max_iterations", &ExampleOptions::max_iterations, AtLeast{1}, "Iterations."),
//           field("poles", &ExampleOptions::poles, Each{GreaterThan{0}}, "Filter poles [rad/s]."),
//           field("hold", &ExampleOptions::hold, "Intersample behaviour of u.")};
//     }
//     void validate() const { validate_fields(*this); }
//   };
//
// A bad value throws InvalidArgument naming the full path, the value and the rule:
// "FeedbackIdentificationOptions.output_error.substeps is 0; it must be >= 1". A field whose
// type has fields() of its own is checked recursively; an enum must name one of its
// enumerators; a vector's rule applies to each element ("poles[2] is -1; it must be > 0");
// an empty optional passes. Relations between fields go in an optional member
// `void check_relations(const std::string& path) const`, called after the per-field rules.
#pragma once

#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "ctid/core/error.h"

namespace ctid {

// --- Enumerations with names -------------------------------------------------------------

/// One value of an enumeration with its name (used in JSON, Python and on the command line)
/// and one line of documentation. An enumeration gets names by a function found by
/// argument-dependent lookup, `constexpr std::span<const Enumerator<E>> enumerators(E)`.
template <class E>
struct Enumerator {
  E value;
  std::string_view name;
  std::string_view doc;
};

template <class E>
concept NamedEnum = std::is_enum_v<E> && requires(E e) {
  { enumerators(e) } -> std::convertible_to<std::span<const Enumerator<E>>>;
};

/// The name of `value` ("?" if it is none of the enumerators, e.g. a cast integer).
template <NamedEnum E>
std::string_view enum_name(E value) {
  for (const auto& e : enumerators(E{})) {
    if (e.value == value) return e.name;
  }
  return "?";
}

/// The enumerator called `name`, or nullopt.
template <NamedEnum E>
std::optional<E> enum_from_name(std::string_view name) {
  for (const auto& e : enumerators(E{})) {
    if (e.name == name) return e.value;
  }
  return std::nullopt;
}

/// "a, b or c": the names of E, for messages.
template <NamedEnum E>
std::string enum_names(std::string_view last_separator = " or ") {
  std::string out;
  const auto all = enumerators(E{});
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i > 0) out += (i + 1 == all.size()) ? std::string(last_separator) : std::string(", ");
    out += all[i].name;
  }
  return out;
}

// --- Rules ---------------------------------------------------------------------------------
// A rule has `bool holds(double) const` and `std::string text() const` ("must be >= 1").

namespace internal {
inline std::string number_text(double x) { return concat(x); }
}  // namespace internal

/// No constraint beyond the field's type.
struct AnyValue {
  bool holds(double) const { return true; }
  std::string text() const { return ""; }
};
struct AtLeast {
  double bound;
  bool holds(double x) const { return x >= bound; }
  std::string text() const { return ">= " + internal::number_text(bound); }
};
struct AtMost {
  double bound;
  bool holds(double x) const { return x <= bound; }
  std::string text() const { return "<= " + internal::number_text(bound); }
};
struct GreaterThan {
  double bound;
  bool holds(double x) const { return x > bound; }
  std::string text() const { return "> " + internal::number_text(bound); }
};
/// low < x < high (open), or with closed ends where asked.
struct Between {
  double low;
  double high;
  bool low_closed = false;
  bool high_closed = false;
  bool holds(double x) const {
    return (low_closed ? x >= low : x > low) && (high_closed ? x <= high : x < high);
  }
  std::string text() const {
    return std::string("in ") + (low_closed ? "[" : "(") + internal::number_text(low) + ", " +
           internal::number_text(high) + (high_closed ? "]" : ")");
  }
};
/// A rule applied to every element of a vector field.
template <class Rule>
struct Each {
  Rule rule;
  bool holds(double x) const { return rule.holds(x); }
  std::string text() const { return rule.text(); }
};
template <class Rule>
Each(Rule) -> Each<Rule>;
/// A finite value (not +-inf; NaN is always rejected) that also follows `rule`, for one-sided
/// bounds where infinity would otherwise pass: Finite{GreaterThan{0}} reads "finite and > 0".
template <class Rule = AnyValue>
struct Finite {
  Rule rule{};
  bool holds(double x) const { return std::isfinite(x) && rule.holds(x); }
  std::string text() const {
    const std::string inner = rule.text();
    return inner.empty() ? std::string("finite") : "finite and " + inner;
  }
};
template <class Rule>
Finite(Rule) -> Finite<Rule>;

// --- Fields --------------------------------------------------------------------------------

/// One field: its name, where it lives (a member of the struct or of a base), its rule, its doc,
/// and its command-line spelling when that is not the name with '_' -> '-' (flag_spelling).
template <class Owner, class T, class Rule>
struct Field {
  using value_type = T;
  std::string_view name;
  T Owner::*member;
  Rule rule;
  std::string_view doc;
  std::string_view flag{};
  bool flag_given = false;

  /// This field spelt `spelling` on the command line (without "--"): a long flag, or for a
  /// field whose type has fields() of its own the prefix of their flags ("" adds none).
  constexpr Field with_flag(std::string_view spelling) const {
    Field spelt = *this;
    spelt.flag = spelling;
    spelt.flag_given = true;
    return spelt;
  }
};

template <class Owner, class T, class Rule>
constexpr Field<Owner, T, Rule> field(std::string_view name, T Owner::*member, Rule rule,
                                      std::string_view doc) {
  return {name, member, rule, doc, {}, false};
}
template <class Owner, class T>
constexpr Field<Owner, T, AnyValue> field(std::string_view name, T Owner::*member,
                                          std::string_view doc) {
  return {name, member, AnyValue{}, doc, {}, false};
}

/// A struct that lists its fields.
template <class S>
concept HasFields = requires {
  { S::type_name } -> std::convertible_to<std::string_view>;
  S::fields();
};

/// Calls f(field) for every field of S, in the listed order.
template <HasFields S, class F>
constexpr void for_each_field(F&& f) {
  std::apply([&](const auto&... each) { (f(each), ...); }, S::fields());
}

/// The names of S's fields, in order.
template <HasFields S>
std::vector<std::string> field_names() {
  std::vector<std::string> names;
  for_each_field<S>([&](const auto& f) { names.emplace_back(f.name); });
  return names;
}

/// Joins two field lists (e.g. a base's and a derived struct's).
template <class... A, class... B>
constexpr auto join_fields(const std::tuple<A...>& a, const std::tuple<B...>& b) {
  return std::tuple_cat(a, b);
}

/// Sets every field of `to` that `from` has under the same name and type to `from`'s value:
/// the settings two options structs share (RefinedIvOptions' max_iterations, noise, ... in
/// MimoRefinedIvOptions) pass from one to the other by their fields() lists, not restated.
template <HasFields To, HasFields From>
void assign_shared_fields(To& to, const From& from) {
  for_each_field<To>([&](const auto& t) {
    using T = typename std::decay_t<decltype(t)>::value_type;
    for_each_field<From>([&](const auto& s) {
      if constexpr (std::is_same_v<T, typename std::decay_t<decltype(s)>::value_type>) {
        if (t.name == s.name) to.*(t.member) = from.*(s.member);
      }
    });
  });
}

/// The names of To's fields that From has too, with the same type (assign_shared_fields).
template <HasFields To, HasFields From>
std::vector<std::string> shared_field_names() {
  std::vector<std::string> names;
  for_each_field<To>([&](const auto& t) {
    using T = typename std::decay_t<decltype(t)>::value_type;
    for_each_field<From>([&](const auto& s) {
      if constexpr (std::is_same_v<T, typename std::decay_t<decltype(s)>::value_type>) {
        if (t.name == s.name) names.emplace_back(t.name);
      }
    });
  });
  return names;
}

// --- Command-line spellings ---------------------------------------------------------------
// One vocabulary (docs/decisions/0046): a field's name is its Python keyword and JSON key; its
// flag is "--" + flag_spelling. A field whose type (or optional type) has fields() of its own
// gives its fields' flags, prefixed by its spelling and '-' when it carries one, unprefixed
// otherwise; an optional one also has a flag of its own that switches it on. A struct with
// `static constexpr std::string_view flag_form` (e.g. "MIN:MAX") is one flag, its fields given
// in order in that form.

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};
template <class T>
struct is_optional : std::false_type {};
template <class T>
struct is_optional<std::optional<T>> : std::true_type {};

/// T without std::optional around it.
template <class T>
struct without_optional {
  using type = T;
};
template <class T>
struct without_optional<std::optional<T>> {
  using type = T;
};

/// A struct whose fields get flags of their own (not one flag in a `flag_form`).
template <class T>
concept HasFieldFlags = HasFields<T> && !requires {
  T::flag_form;
};

/// The spelling a field carries, or its name with '_' -> '-'.
template <class F>
std::string flag_spelling(const F& f) {
  std::string spelling(f.flag_given ? f.flag : f.name);
  for (char& c : spelling) c = c == '_' ? '-' : c;
  return spelling;
}

/// One flag of a struct's fields: the field's dotted path below the struct
/// ("refined_iv.max_iterations"), the long flag without "--" ("max-iterations") and its doc.
struct FieldFlag {
  std::string path;
  std::string flag;
  std::string_view doc;
};

template <HasFields S>
void collect_field_flags(std::vector<FieldFlag>& out, const std::string& path_prefix,
                         const std::string& flag_prefix) {
  for_each_field<S>([&](const auto& f) {
    using T = typename std::decay_t<decltype(f)>::value_type;
    using Inner = typename without_optional<T>::type;
    const std::string path = path_prefix + std::string(f.name);
    if constexpr (HasFieldFlags<Inner>) {
      if constexpr (is_optional<T>::value)
        out.push_back({path, flag_prefix + flag_spelling(f), f.doc});
      const std::string prefix = f.flag_given && !f.flag.empty() ? flag_spelling(f) + "-" : "";
      collect_field_flags<Inner>(out, path + ".", flag_prefix + prefix);
    } else {
      out.push_back({path, flag_prefix + flag_spelling(f), f.doc});
    }
  });
}

/// Every flag of S's fields, in the listed order (nested fields in place).
template <HasFields S>
std::vector<FieldFlag> field_flags() {
  std::vector<FieldFlag> out;
  collect_field_flags<S>(out, "", "");
  return out;
}

// --- Validation ----------------------------------------------------------------------------

template <HasFields S>
void validate_fields(const S& object, const std::string& path);

namespace internal {

template <class T, class Rule>
void check_value(const T& value, const std::string& path, const Rule& rule) {
  if constexpr (HasFields<T>) {
    validate_fields(value, path);
  } else if constexpr (is_optional<T>::value) {
    if (value) check_value(*value, path, rule);
  } else if constexpr (is_vector<T>::value) {
    for (std::size_t i = 0; i < value.size(); ++i) {
      check_value(value[i], path + "[" + std::to_string(i) + "]", rule);
    }
  } else if constexpr (NamedEnum<T>) {
    require(enum_name(value) != "?", path, " is ", static_cast<long long>(value),
            "; it must be one of ", enum_names<T>());
  } else if constexpr (std::is_same_v<T, bool>) {
    // no rule applies to a flag
  } else if constexpr (std::is_arithmetic_v<T>) {
    const double x = static_cast<double>(value);
    if constexpr (std::is_floating_point_v<T>) {
      require(!std::isnan(x), path, " is NaN; it must be a number");
    }
    require(rule.holds(x), path, " is ", value, "; it must be ", rule.text());
  }
}

}  // namespace internal

/// Checks every field of `object` against its rule, recursively, then its relations; throws
/// InvalidArgument naming the first bad field by its full path (`path` names `object`).
template <HasFields S>
void validate_fields(const S& object, const std::string& path) {
  for_each_field<S>([&](const auto& f) {
    internal::check_value(object.*(f.member), path + "." + std::string(f.name), f.rule);
  });
  if constexpr (requires { object.check_relations(path); }) object.check_relations(path);
}

/// The same, with the struct's own name as the path.
template <HasFields S>
void validate_fields(const S& object) {
  validate_fields(object, std::string(S::type_name));
}

}  // namespace ctid

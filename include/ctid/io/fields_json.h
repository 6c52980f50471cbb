// JSON for any struct that lists its fields (ctid/core/fields.h): fields_to_json writes one key
// per field, named as the field; fields_from_json reads them back, starting from the struct's
// defaults (a missing key keeps its default), rejecting unknown keys and values of the wrong
// type with the source and the field's full path, then validates. Numbers are written with
// full precision (they read back bit-identical); a non-finite double is written as null and
// read back as NaN; a complex number as [real, imag]; enumerations by name; vectors, optionals
// and nested structs recursively.
// Other types (models, transfer functions) are written by an overload
// `nlohmann::json to_json_value(const T&)` and read by `T from_json_value(const
// nlohmann::json&, std::type_identity<T>, const std::string& where)`, both found by
// argument-dependent lookup (io/model_json.h has them for the model types).
#pragma once

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "ctid/core/error.h"
#include "ctid/core/fields.h"

namespace ctid::io {

template <HasFields S>
nlohmann::json fields_to_json(const S& object);
template <HasFields S>
void fields_from_json(const nlohmann::json& value, S& object, const std::string& where);

namespace internal {

/// A double as JSON: a number, or null for NaN and infinities (JSON has neither).
inline nlohmann::json number_or_null(double x) {
  return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr);
}

/// 2π, for documents that store frequencies in Hz.
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

template <class T>
struct is_complex : std::false_type {};
template <class T>
struct is_complex<std::complex<T>> : std::true_type {};

inline std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

template <class T>
nlohmann::json value_json(const T& value) {
  if constexpr (HasFields<T>) {
    return fields_to_json(value);
  } else if constexpr (is_optional<T>::value) {
    return value ? value_json(*value) : nlohmann::json(nullptr);
  } else if constexpr (is_vector<T>::value) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& each : value) out.push_back(value_json(each));
    return out;
  } else if constexpr (NamedEnum<T>) {
    return std::string(enum_name(value));
  } else if constexpr (std::is_same_v<T, bool> || std::is_integral_v<T>) {
    return value;
  } else if constexpr (std::is_floating_point_v<T>) {
    return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
  } else if constexpr (std::is_same_v<T, std::string>) {
    return value;
  } else if constexpr (is_complex<T>::value) {
    return nlohmann::json::array({value_json(value.real()), value_json(value.imag())});
  } else if constexpr (std::is_base_of_v<Eigen::MatrixBase<T>, T>) {
    using Scalar = typename T::Scalar;
    nlohmann::json out = nlohmann::json::array();
    if (value.cols() == 1 && T::ColsAtCompileTime == 1) {
      for (Eigen::Index i = 0; i < value.size(); ++i) out.push_back(value_json(Scalar(value(i))));
    } else {
      for (Eigen::Index r = 0; r < value.rows(); ++r) {
        nlohmann::json row = nlohmann::json::array();
        for (Eigen::Index c = 0; c < value.cols(); ++c)
          row.push_back(value_json(Scalar(value(r, c))));
        out.push_back(std::move(row));
      }
    }
    return out;
  } else {
    return to_json_value(value);
  }
}

[[noreturn]] inline void wrong_type(const std::string& where, const char* expected,
                                    const nlohmann::json& value) {
  throw InvalidArgument(where + ": expected " + expected + ", got " +
                        std::string(value.type_name()));
}

inline double number_json(const nlohmann::json& value, const std::string& where) {
  if (value.is_null()) return std::numeric_limits<double>::quiet_NaN();
  if (!value.is_number()) wrong_type(where, "a number", value);
  return value.get<double>();
}

/// A double, or a complex number written as [real, imag].
template <class Scalar>
Scalar scalar_json(const nlohmann::json& value, const std::string& where) {
  if constexpr (is_complex<Scalar>::value) {
    if (!value.is_array() || value.size() != 2) {
      throw InvalidArgument(where + ": expected [real, imag]");
    }
    return Scalar(number_json(value[0], where + "[0]"), number_json(value[1], where + "[1]"));
  } else {
    return static_cast<Scalar>(number_json(value, where));
  }
}

template <class T>
void value_from_json(const nlohmann::json& value, T& out, const std::string& where);

/// A T read from `value`: default-constructed and filled, or (types without a default) made
/// by the hook `T from_json_value(const nlohmann::json&, std::type_identity<T>, where)`.
template <class T>
T read_value(const nlohmann::json& value, const std::string& where) {
  if constexpr (std::is_default_constructible_v<T>) {
    // Value-initialised: GCC 12 at -O3 takes `T out{}` of an aggregate holding a vector in a
    // nested struct (StructureFit's ModelStructure) for maybe-uninitialized.
    T out = T();
    value_from_json(value, out, where);
    return out;
  } else {
    return from_json_value(value, std::type_identity<T>{}, where);
  }
}

template <class T>
void value_from_json(const nlohmann::json& value, T& out, const std::string& where) {
  if constexpr (HasFields<T>) {
    fields_from_json(value, out, where);
  } else if constexpr (is_optional<T>::value) {
    if (value.is_null()) {
      out.reset();
    } else if (out) {
      value_from_json(value, *out, where);
    } else {
      out = read_value<typename T::value_type>(value, where);
    }
  } else if constexpr (is_vector<T>::value) {
    if (!value.is_array()) wrong_type(where, "an array", value);
    T result;
    result.reserve(value.size());
    for (std::size_t i = 0; i < value.size(); ++i) {
      result.push_back(
          read_value<typename T::value_type>(value[i], where + "[" + std::to_string(i) + "]"));
    }
    out = std::move(result);
  } else if constexpr (NamedEnum<T>) {
    if (!value.is_string()) wrong_type(where, "a name", value);
    const auto parsed = enum_from_name<T>(value.get<std::string>());
    if (!parsed) {
      throw InvalidArgument(where + ": '" + value.get<std::string>() + "' is not one of " +
                            enum_names<T>());
    }
    out = *parsed;
  } else if constexpr (std::is_same_v<T, bool>) {
    if (!value.is_boolean()) wrong_type(where, "true or false", value);
    out = value.get<bool>();
  } else if constexpr (std::is_integral_v<T> && std::is_unsigned_v<T>) {
    if (!value.is_number_integer()) wrong_type(where, "an integer", value);
    if (!value.is_number_unsigned()) {
      throw InvalidArgument(where + ": " + value.dump() + " is out of range");
    }
    const auto wide = value.get<unsigned long long>();
    if (wide > static_cast<unsigned long long>(std::numeric_limits<T>::max())) {
      throw InvalidArgument(where + ": " + std::to_string(wide) + " is out of range");
    }
    out = static_cast<T>(wide);
  } else if constexpr (std::is_integral_v<T>) {
    if (!value.is_number_integer()) wrong_type(where, "an integer", value);
    const auto wide = value.get<long long>();
    if (wide < static_cast<long long>(std::numeric_limits<T>::min()) ||
        (wide > 0 && static_cast<unsigned long long>(wide) >
                         static_cast<unsigned long long>(std::numeric_limits<T>::max()))) {
      throw InvalidArgument(where + ": " + std::to_string(wide) + " is out of range");
    }
    out = static_cast<T>(wide);
  } else if constexpr (std::is_floating_point_v<T>) {
    out = static_cast<T>(number_json(value, where));
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!value.is_string()) wrong_type(where, "a string", value);
    out = value.get<std::string>();
  } else if constexpr (is_complex<T>::value) {
    out = scalar_json<T>(value, where);
  } else if constexpr (std::is_base_of_v<Eigen::MatrixBase<T>, T>) {
    using Scalar = typename T::Scalar;
    if (!value.is_array()) wrong_type(where, "an array", value);
    if (T::ColsAtCompileTime == 1) {
      out.resize(static_cast<Eigen::Index>(value.size()), 1);
      for (std::size_t i = 0; i < value.size(); ++i) {
        out(static_cast<Eigen::Index>(i)) =
            scalar_json<Scalar>(value[i], where + "[" + std::to_string(i) + "]");
      }
    } else {
      const auto rows = static_cast<Eigen::Index>(value.size());
      const auto cols = rows == 0 ? Eigen::Index{0} : static_cast<Eigen::Index>(value[0].size());
      out.resize(rows, cols);
      for (Eigen::Index r = 0; r < rows; ++r) {
        const auto& row = value[static_cast<std::size_t>(r)];
        const std::string row_where = where + "[" + std::to_string(r) + "]";
        if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != cols) {
          throw InvalidArgument(row_where + ": expected a row of " + std::to_string(cols) +
                                " numbers");
        }
        for (Eigen::Index c = 0; c < cols; ++c) {
          out(r, c) = scalar_json<Scalar>(row[static_cast<std::size_t>(c)],
                                          row_where + "[" + std::to_string(c) + "]");
        }
      }
    }
  } else {
    out = from_json_value(value, std::type_identity<T>{}, where);
  }
}

}  // namespace internal

/// {"field": value, ...} for every field of `object`, in the listed order.
template <HasFields S>
nlohmann::json fields_to_json(const S& object) {
  nlohmann::json out = nlohmann::json::object();
  for_each_field<S>(
      [&](const auto& f) { out[std::string(f.name)] = internal::value_json(object.*(f.member)); });
  return out;
}

/// Reads the fields present in `value` into `object` (others keep their values); `where`
/// names the object in messages ("options.json: FeedbackIdentificationOptions.output_error").
template <HasFields S>
void fields_from_json(const nlohmann::json& value, S& object, const std::string& where) {
  if (!value.is_object()) internal::wrong_type(where, "an object", value);
  for (const auto& item : value.items()) {
    // Named references, not a structured binding, which clang before 16 cannot capture in a
    // lambda (the fuzz build, fuzz/, uses clang 14).
    const std::string& key = item.key();
    const nlohmann::json& element = item.value();
    bool known = false;
    for_each_field<S>([&](const auto& f) {
      if (!known && f.name == key) {
        known = true;
        internal::value_from_json(element, object.*(f.member), where + "." + key);
      }
    });
    if (!known) {
      throw InvalidArgument(where + ": unknown field '" + key + "'; the fields of " +
                            std::string(S::type_name) + " are " +
                            internal::join_names(field_names<S>()));
    }
  }
}

/// An options struct from JSON: its defaults, overridden by the keys present, then validated.
template <HasFields S>
S options_from_json(const nlohmann::json& value, const std::string& source) {
  S object{};
  fields_from_json(value, object, source + ": " + std::string(S::type_name));
  try {
    object.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(source + ": " + e.what());
  }
  return object;
}

}  // namespace ctid::io

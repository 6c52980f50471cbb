// Python classes derived from a struct's field list (ctid/core/fields.h): attributes with the
// fields' docs, a keyword-only constructor that rejects unknown keywords, validate(), a repr,
// equality, and the class attributes `fields` (names in order) and `field_docs`. Options are
// read/write; results are read-only. Enumerations are bound from their enumerators. No field
// is named here: adding one to the C++ list adds it to Python. Every options class is also
// registered for JSON (io/fields_json.h): ctid.options_to_json / ctid.options_from_json.
#pragma once

#include <algorithm>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common.h"
#include "ctid/core/fields.h"
#include "ctid/io/fields_json.h"
#include "ctid/io/json.h"
#include "ctid/io/model_json.h"

namespace ctid::python {

/// Binds E as a Python enum named `name`, its values and docs from enumerators(E). A value's
/// name is the command line's ("ssi-cov", what JSON holds and .name gives); one with a hyphen
/// is also an attribute with an underscore (ctid.OmaMethod.ssi_cov), as Python needs.
template <NamedEnum E>
py::enum_<E> bind_enum(py::module_& m, const char* name, const char* doc) {
  py::enum_<E> e(m, name, doc);
  for (const auto& each : enumerators(E{})) e.value(each.name.data(), each.value, each.doc.data());
  for (const auto& each : enumerators(E{})) {
    std::string identifier(each.name);
    if (identifier.find('-') == std::string::npos) continue;
    std::replace(identifier.begin(), identifier.end(), '-', '_');
    e.attr(identifier.c_str()) = py::cast(each.value);
  }
  return e;
}

namespace internal {

template <HasFields S>
std::string fields_repr(const py::object& self) {
  std::string out = std::string(S::type_name) + "(";
  bool first = true;
  for_each_field<S>([&](const auto& f) {
    out += (first ? "" : ", ") + std::string(f.name) + "=" +
           py::cast<std::string>(py::repr(self.attr(f.name.data())));
    first = false;
  });
  return out + ")";
}

/// Field values compared for ==: NumPy arrays by shape and elements (NaN equal to NaN, so a
/// result read back from a document equals the one written), anything else by its own ==.
inline bool values_equal(const py::object& a, const py::object& b) {
  if (py::hasattr(a, "shape") || py::hasattr(b, "shape")) {
    const py::module_ np = py::module_::import("numpy");
    return np.attr("array_equal")(a, b, py::arg("equal_nan") = true).cast<bool>();
  }
  return a.equal(b);
}

template <HasFields S, class Class>
void add_common(Class& cls) {
  const auto names = field_names<S>();
  py::tuple fields(names.size());
  py::dict docs;
  std::size_t i = 0;
  for_each_field<S>([&](const auto& f) {
    fields[i++] = py::str(f.name.data());
    docs[py::str(f.name.data())] = py::str(f.doc.data());
  });
  cls.attr("fields") = fields;
  cls.attr("field_docs") = docs;
  cls.def("__repr__", &fields_repr<S>);
  cls.def("__eq__", [](const py::object& a, const py::object& b) {
    if (!py::isinstance(b, py::type::of(a))) return false;
    bool equal = true;
    for_each_field<S>([&](const auto& f) {
      equal = equal && values_equal(a.attr(f.name.data()), b.attr(f.name.data()));
    });
    return equal;
  });
}

/// JSON text of an options object, and an options object (as a Python object) from JSON text.
struct OptionsJson {
  std::function<std::string(const py::object&)> write;
  std::function<py::object(const std::string&)> read;
};

/// Every options class bound by bind_options, by its type_name.
inline std::map<std::string, OptionsJson>& options_json_registry() {
  static std::map<std::string, OptionsJson> registry;
  return registry;
}

template <HasFields S>
void register_options_json() {
  const std::string name(S::type_name);
  options_json_registry()[name] = OptionsJson{
      [](const py::object& object) { return io::fields_to_json(object.cast<const S&>()).dump(); },
      [name](const std::string& text) {
        const std::string source = "options_from_json";
        // io::parse_json refuses documents nested too deeply before parsing them.
        const nlohmann::json document = io::parse_json(text, source + ": " + name);
        return py::cast(io::options_from_json<S>(document, source));
      }};
}

inline const OptionsJson& options_json_of(const std::string& name) {
  const auto& registry = options_json_registry();
  const auto found = registry.find(name);
  if (found == registry.end()) {
    std::vector<std::string> names;
    for (const auto& [each, json] : registry) names.push_back(each);
    throw py::value_error("'" + name + "' is not an options class; the options classes are " +
                          join(names));
  }
  return found->second;
}

}  // namespace internal

/// The module functions behind ctid.options_to_json / ctid.options_from_json (python/ctid):
/// `_options_to_json_text(options) -> str`, `_options_from_json_text(name, text)` and
/// `_options_classes() -> list of names`, over the classes bound by bind_options.
inline void bind_options_json(py::module_& m) {
  m.def(
      "_options_to_json_text",
      [](const py::object& options) {
        const auto name = py::cast<std::string>(py::type::of(options).attr("__name__"));
        return internal::options_json_of(name).write(options);
      },
      py::arg("options"), "JSON text of an options object (every field, by name).");
  m.def(
      "_options_from_json_text",
      [](const std::string& name, const std::string& text) {
        return internal::options_json_of(name).read(text);
      },
      py::arg("name"), py::arg("text"),
      "Options class `name` from JSON text: defaults, then the keys given, then validate().");
  m.def(
      "_options_classes",
      [] {
        std::vector<std::string> names;
        for (const auto& [name, json] : internal::options_json_registry()) names.push_back(name);
        return names;
      },
      "Names of the options classes reachable from JSON.");
}

/// An options struct as a Python class S.type_name: S(field=value, ...), read/write attributes,
/// validate() (ValueError naming the field path, value and rule), repr, ==, `fields`, and
/// `field_rules` (each field's rule as text, "" for none); registered for JSON.
template <HasFields S>
py::class_<S> bind_options(py::module_& m, const char* doc) {
  py::class_<S> cls(m, S::type_name.data(), doc);
  for_each_field<S>(
      [&](const auto& f) { cls.def_readwrite(f.name.data(), f.member, f.doc.data()); });
  const std::string name(S::type_name);
  const auto names = field_names<S>();
  cls.def(
      py::init([name, names](const py::kwargs& kwargs) {
        check_keywords(name, kwargs, names);
        const S defaults{};
        py::object object = py::cast(defaults);
        for (const auto& item : kwargs) py::setattr(object, item.first, item.second);
        return object.cast<S>();
      }),
      ("Keyword-only constructor; fields: " + join(names) + ". Unknown keywords raise TypeError.")
          .c_str());
  cls.def(
      "validate", [](const S& self) { self.validate(); },
      "Raise ValueError naming the first bad field (its full path), its value and the rule.");
  py::dict rules;
  for_each_field<S>([&](const auto& f) { rules[py::str(f.name.data())] = py::str(f.rule.text()); });
  cls.attr("field_rules") = rules;
  internal::add_common<S>(cls);
  internal::register_options_json<S>();
  return cls;
}

/// A result struct as a Python class: read-only attributes, repr, ==, `fields`. Further methods
/// (converged(), brief_report(), ...) are added by the caller on the returned class.
template <HasFields S, class... Bases>
py::class_<S, Bases...> bind_result(py::module_& m, const char* doc) {
  py::class_<S, Bases...> cls(m, S::type_name.data(), doc);
  for_each_field<S>(
      [&](const auto& f) { cls.def_readonly(f.name.data(), f.member, f.doc.data()); });
  internal::add_common<S>(cls);
  return cls;
}

}  // namespace ctid::python

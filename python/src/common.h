// Shared helpers of the ctid Python bindings: the keyword check of the options classes that
// fields.h derives from each struct's field list, and functions that take their options either
// as one options object or as keyword arguments. No numerics live here.
#pragma once

#include <algorithm>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/complex.h>
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/operators.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

namespace ctid::python {

namespace py = pybind11;

void bind_core(py::module_& m);
void bind_simulation(py::module_& m);
void bind_frequency(py::module_& m);
void bind_oma(py::module_& m);
void bind_estimation(py::module_& m);
void bind_refined_iv(py::module_& m);
void bind_frf_fit(py::module_& m);
void bind_identification(py::module_& m);
void bind_process_model(py::module_& m);
void bind_delayed_feedback(py::module_& m);
void bind_study(py::module_& m);
void bind_io(py::module_& m);
void bind_command_line(py::module_& m);
void bind_response(py::module_& m);

inline std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

/// Raises TypeError unless every key of `kwargs` is one of `fields`.
inline void check_keywords(const std::string& where, const py::kwargs& kwargs,
                           const std::vector<std::string>& fields) {
  for (const auto& item : kwargs) {
    const auto key = py::cast<std::string>(item.first);
    if (std::find(fields.begin(), fields.end(), key) == fields.end()) {
      throw py::type_error(where + "() got an unexpected keyword argument '" + key +
                           "'; valid keywords: " + join(fields));
    }
  }
}

/// The options of a call: `options` itself, or T(**kwargs); both at once is a TypeError, and
/// an unknown keyword names the function and the valid keywords.
template <class T>
T options_from(const std::string& function, const std::optional<T>& options,
               const py::kwargs& kwargs) {
  if (options && !kwargs.empty()) {
    throw py::type_error(function + "() takes either options=... or keyword options, not both");
  }
  if (options) return *options;
  const py::object type = py::type::of<T>();
  const auto fields = py::cast<std::vector<std::string>>(type.attr("fields"));
  check_keywords(function, kwargs, fields);
  return type(**kwargs).template cast<T>();
}

}  // namespace ctid::python

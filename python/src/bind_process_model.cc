// Python binding of the process models (process_model/process_model.h, decision 0040; its
// types and identify's overload reached through identification/identification.h):
// ctid.process_model(data, "P1D", start={...}, fixed={...}, bounds={...}) runs what
// `ctid fit --process P1D` runs (identify's process-model overload). The options and the
// result are derived from their C++ field lists (fields.h).
#include <map>
#include <optional>
#include <string>
#include <utility>

#include <pybind11/stl.h>

#include "common.h"
#include "ctid/identification/identification.h"
#include "fields.h"

namespace ctid::python {
namespace {

using Bounds = std::map<std::string, std::pair<std::optional<double>, std::optional<double>>>;

ProcessParameterSetting& setting(ProcessModelOptions& o, const std::string& name) {
  for (ProcessParameterSetting& s : o.parameters) {
    if (s.name == name) return s;
  }
  o.parameters.push_back(ProcessParameterSetting{name, {}, false, {}, {}});
  return o.parameters.back();
}

}  // namespace

void bind_process_model(py::module_& m) {
  bind_options<ProcessParameterSetting>(
      m, "Start, held value and bounds of one process-model parameter (K, Tp1, ..., Td).");
  bind_options<ProcessModelOptions>(
      m, "Options of process_model: parameter settings, the largest delay scanned, iterations.");
  bind_result<ProcessModelResult>(
      m, "A process model: parameters with standard errors, fit, verdict (ctid fit --process).")
      .def("converged", &ProcessModelResult::converged, "termination == converged.")
      .def("brief_report", &ProcessModelResult::brief_report,
           "'converged after N iterations' (with the message when it did not converge).")
      .def("parameter", &ProcessModelResult::parameter, py::arg("name"),
           "The value of a parameter by its procest name.")
      .def("standard_error", &ProcessModelResult::standard_error, py::arg("name"),
           "One standard error of a parameter (0 for a held one).")
      .def("transfer_function", &ProcessModelResult::transfer_function,
           "The model as a TransferFunction whose input delay is Td.");

  m.def(
      "process_parameter_names",
      [](const std::string& structure) {
        return ProcessStructure::parse(structure).parameter_names();
      },
      py::arg("structure"),
      "The parameters of a process model in order, e.g. ['K', 'Tp1', 'Td'] for 'P1D'.");
  m.def(
      "process_model",
      [](const SampledData& data, const std::string& structure,
         const std::optional<ProcessModelOptions>& options,
         const std::optional<std::map<std::string, double>>& start,
         const std::optional<std::map<std::string, double>>& fixed,
         const std::optional<Bounds>& bounds, const std::optional<double>& max_delay) {
        const ProcessStructure s = ProcessStructure::parse(structure);
        ProcessModelOptions o = options.value_or(ProcessModelOptions{});
        for (const auto& [name, value] : start.value_or(std::map<std::string, double>{})) {
          setting(o, name).value = value;
        }
        for (const auto& [name, value] : fixed.value_or(std::map<std::string, double>{})) {
          ProcessParameterSetting& p = setting(o, name);
          require(!p.value, "parameter '", name, "' is given both a start and a held value");
          p.value = value;
          p.fixed = true;
        }
        for (const auto& [name, range] : bounds.value_or(Bounds{})) {
          ProcessParameterSetting& p = setting(o, name);
          p.lower = range.first;
          p.upper = range.second;
        }
        if (max_delay) o.max_delay = *max_delay;
        py::gil_scoped_release release;
        return identify(data, s, o);
      },
      py::arg("data"), py::arg("structure"), py::arg("options") = py::none(), py::kw_only(),
      py::arg("start") = py::none(), py::arg("fixed") = py::none(), py::arg("bounds") = py::none(),
      py::arg("max_delay") = py::none(),
      "Fit a process model named as procest names it ('P1D', 'P2DU', 'P1DI', ...) to `data` "
      "by continuous-time output error, the dead time off the sample grid, as `ctid fit "
      "--process` does. start / fixed: {name: value}; bounds: {name: (lower, upper)}, either "
      "side None; max_delay [s]: the largest dead time the automatic start scans.");
}

}  // namespace ctid::python

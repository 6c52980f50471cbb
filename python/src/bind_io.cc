// Python bindings of the result documents (io/documents.h): ctid.read_result(path) returns the
// result a document holds as the Python class of its C++ type; ctid.result_to_json(result)
// and ctid.write_result(path, result) write one.
#include <filesystem>
#include <variant>

#include <pybind11/stl/filesystem.h>

#include "common.h"
#include "ctid/io/documents.h"
#include "ctid/io/file.h"
#include "ctid/io/mimo_data_csv.h"
#include "fields.h"

namespace ctid::python {
namespace {

// One overload per result type (a variant argument would need a default-constructible first
// alternative, which EstimationResult is not).
template <class... T>
void bind_writers(py::module_& m, std::variant<T...>*) {
  (m.def(
       "result_to_json",
       [](const T& result, int indent) {
         return io::to_json(io::ResultDocument(result)).dump(indent);
       },
       py::arg("result"), py::arg("indent") = 2,
       "The document of a result as JSON text (read back by read_result bit for bit)."),
   ...);
  (m.def(
       "write_result",
       [](const std::filesystem::path& path, const T& result, bool overwrite) {
         io::write_result(path, io::ResultDocument(result),
                          overwrite ? io::Overwrite::yes : io::Overwrite::no);
       },
       py::arg("path"), py::arg("result"), py::arg("overwrite") = false,
       "Writes the document of a result (refuses an existing file unless overwrite)."),
   ...);
}

}  // namespace

void bind_io(py::module_& m) {
  bind_result<io::DelayedFeedbackResult>(
      m,
      "What ctid feedback computes: the identification at the known or scanned delay, and "
      "the scan when the delay was unknown (a delayed_feedback_result document).");
  m.def(
      "read_result", [](const std::filesystem::path& path) { return io::read_result(path); },
      py::arg("path"),
      "The result in a document written by ctid (fit -o, validate -o, frf -o X.json, study's "
      "summary.json, feedback -o, structure -o, fit-frf -o) or by write_result: EstimationResult, "
      "ModeRelocationResult, "
      "InputDelayScanResult, ValidationReport, Frf, StudySummary, DelayedFeedbackResult, "
      "StructureScanResult, MimoEstimationResult or FrfMatrixFitResult, "
      "chosen by its \"type\". "
      "Raises InvalidArgument for an unknown type or version or a bad field.");
  m.def("result_document_types", &io::result_document_types,
        "The \"type\" values read_result reads.");
  bind_writers(m, static_cast<io::ResultDocument*>(nullptr));

  bind_options<io::MimoCsvColumns>(
      m, "Which CSV columns hold a MimoData's signals: names or ranges 'A:B' (file order).");
  m.def(
      "read_mimo_data",
      [](const std::filesystem::path& path, const std::optional<io::MimoCsvColumns>& columns,
         const py::kwargs& kwargs) {
        return io::read_mimo_data(
            path, options_from<io::MimoCsvColumns>("read_mimo_data", columns, kwargs));
      },
      py::arg("path"), py::arg("columns") = py::none(),
      "A MimoData from a CSV file or a .npy array (columns named '0', '1', ...) (MimoCsvColumns or "
      "its fields as keywords, e.g. "
      "inputs=['u1_force', 'u2_force'], outputs=['y1_acc:y28_acc']); channels named after "
      "their columns. Raises InvalidArgument naming the file and a missing or repeated column.");
  m.def(
      "write_mimo_data",
      [](const std::filesystem::path& path, const MimoData& data, const std::string& time_column,
         bool overwrite) {
        io::write_mimo_data(path, data, time_column,
                            overwrite ? io::Overwrite::yes : io::Overwrite::no);
      },
      py::arg("path"), py::arg("data"), py::arg("time_column") = "t", py::arg("overwrite") = false,
      "Writes a MimoData as CSV: the time column, then each channel under its name (references "
      "as r_<input>).");
}

}  // namespace ctid::python

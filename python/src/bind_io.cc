// Python bindings of the result documents (io/documents.h): ctid.read_result(path) returns the
// result a document holds as the Python class of its C++ type; ctid.result_to_json(result)
// and ctid.write_result(path, result) write one. ctid.read_csv / ctid.write_csv read and write
// one record with the command line's column and time-stamp rules (io/sampled_data_csv.h).
#include <filesystem>
#include <variant>

#include <pybind11/stl/filesystem.h>

#include "common.h"
#include "ctid/core/error.h"
#include "ctid/core/preprocessing.h"
#include "ctid/io/csv.h"
#include "ctid/io/documents.h"
#include "ctid/io/file.h"
#include "ctid/io/json.h"
#include "ctid/io/mimo_data_csv.h"
#include "ctid/io/model_json.h"
#include "ctid/io/result_json.h"
#include "ctid/io/sampled_data_csv.h"
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
         return io::json_text(io::to_json(io::ResultDocument(result)), indent);
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

const char* hold_text(Hold hold) { return hold == Hold::zero_order_hold ? "zoh" : "foh"; }

// None, a Hold, or its name as on the command line (zoh, foh) or in full.
std::optional<Hold> hold_argument(const py::object& value) {
  if (value.is_none()) return std::nullopt;
  if (py::isinstance<py::str>(value)) {
    const auto text = value.cast<std::string>();
    if (text == "zoh" || text == "zero_order_hold") return Hold::zero_order_hold;
    if (text == "foh" || text == "first_order_hold") return Hold::first_order_hold;
    throw InvalidArgument("read_csv: input_hold is '" + text + "'; it must be zoh or foh");
  }
  return value.cast<Hold>();
}

// The record of a CSV file as `ctid fit FILE` reads it (apps/ctid/data_flags.cc): the time
// column's uniform step is the sample time (io::sampled_data_from_table's rule) unless
// `sample_time` overrides it (the first stamp, if any, stays the start time) or `resample`
// moves irregular stamps onto a grid of that step; the input hold is the one given, else the
// file's "# input_hold:" declaration, else zero-order hold, and the two must not contradict.
SampledData read_csv_record(const std::filesystem::path& path, const io::CsvColumns& columns,
                            std::optional<double> sample_time, std::optional<double> step,
                            std::optional<Hold> given) {
  const std::string source = path.string();
  columns.validate();
  columns.check_relations(source);
  if (sample_time && step) {
    throw InvalidArgument("read_csv: give sample_time or resample, not both");
  }
  const io::CsvTable table = io::read_csv(path);
  const std::optional<Hold> declared = io::declared_input_hold(table);
  if (declared && given && *declared != *given) {
    throw InvalidArgument(
        ::ctid::internal::concat("read_csv: input_hold ", hold_text(*given), " contradicts ",
                                 source, ":", table.declaration("input_hold")->line,
                                 ", which declares input_hold: ", hold_text(*declared)));
  }
  const Hold hold = given.value_or(declared.value_or(Hold::zero_order_hold));
  const Eigen::VectorXd& input = table.column(columns.input);
  const Eigen::VectorXd& output = table.column(columns.output);
  std::optional<Eigen::VectorXd> reference;
  if (!columns.reference.empty()) reference = table.column(columns.reference);
  const bool stamped = table.has_column(columns.time);
  const auto named = [&](const auto& make) {
    try {
      return make();
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(source + ": " + e.what());
    }
  };
  if (step) {
    if (!stamped) table.column(columns.time);  // throws, naming the columns present
    return named([&] {
      return resample(table.column(columns.time), input, output, reference, *step, hold);
    });
  }
  if (sample_time) {
    const double start = stamped ? table.column(columns.time)(0) : 0.0;
    return named([&] {
      return SampledData(*sample_time, input, output, reference, start).with_input_hold(hold);
    });
  }
  if (!stamped) {
    throw InvalidArgument(::ctid::internal::concat(source, " has no time column '", columns.time,
                                                   "'; give sample_time= (or time=)"));
  }
  try {
    return io::sampled_data_from_table(table, columns).with_input_hold(hold);
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(std::string(e.what()) +
                          "; sample_time= overrides the time column, and resample=H moves "
                          "irregular stamps onto a grid of step H");
  }
}

// The model a model document holds, as the Python class of its "type" (docs/formats.md).
py::object model_from_document(const nlohmann::json& value, const std::string& source) {
  const auto type = value.is_object() ? value.find("type") : value.end();
  const std::string name =
      type != value.end() && type->is_string() ? type->get<std::string>() : std::string();
  if (name == io::kTransferFunctionType) {
    return py::cast(io::transfer_function_from_json(value, source));
  }
  if (name == io::kAdditiveModelType) return py::cast(io::additive_model_from_json(value, source));
  if (name == io::kMimoAdditiveModelType) {
    return py::cast(io::mimo_additive_model_from_json(value, source));
  }
  if (name == io::kDiscreteTransferFunctionType) {
    return py::cast(io::discrete_transfer_function_from_json(value, source));
  }
  if (name == io::kDelayedFeedbackLoopType) {
    return py::cast(io::delayed_feedback_loop_from_json(value, source));
  }
  throw InvalidArgument(::ctid::internal::concat(
      source, ": \"type\" is ", type == value.end() ? "missing" : type->dump(),
      "; a model document is one of ", io::kTransferFunctionType, ", ", io::kAdditiveModelType,
      ", ", io::kMimoAdditiveModelType, ", ", io::kDiscreteTransferFunctionType, ", ",
      io::kDelayedFeedbackLoopType));
}

template <class Model>
void bind_model_writer(py::module_& m) {
  m.def(
      "model_to_json",
      [](const Model& model, int indent) { return io::json_text(io::to_json(model), indent); },
      py::arg("model"), py::arg("indent") = 2,
      "The model document of a model as JSON text (read back by model_from_json bit for bit).");
  m.def(
      "write_model",
      [](const std::filesystem::path& path, const Model& model, bool overwrite) {
        io::write_json(path, io::to_json(model),
                       overwrite ? io::Overwrite::yes : io::Overwrite::no);
      },
      py::arg("path"), py::arg("model"), py::arg("overwrite") = false,
      "Writes the model document of a model (refuses an existing file unless overwrite).");
}

}  // namespace

void bind_io(py::module_& m) {
  m.def("parameter_names", &io::parameter_names, py::arg("model"),
        "Names of the stacked parameters of an AdditiveModel, as the documents and ctid fit "
        "print them: theta1.a1, ..., theta1.b0, theta2.a1, ...");
  bind_result<io::DelayedFeedbackResult>(
      m,
      "What ctid feedback computes: the identification at the known or scanned delay, and "
      "the scan when the delay was unknown (a delayed_feedback_result document).");
  m.def(
      "read_result", [](const std::filesystem::path& path) { return io::read_result(path); },
      py::arg("path"),
      "The result in a document written by ctid (fit -o, validate -o, frf -o X.json, study's "
      "summary.json, feedback -o, structure -o, fit-frf -o, oma -o) or by write_result: "
      "EstimationResult, "
      "ModeRelocationResult, "
      "InputDelayScanResult, ValidationReport, Frf, StudySummary, DelayedFeedbackResult, "
      "StructureScanResult, MimoEstimationResult, FrfMatrixFitResult, MimoFrf or OmaResult, "
      "chosen by its \"type\". "
      "Raises InvalidArgument for an unknown type or version or a bad field.");
  m.def("result_document_types", &io::result_document_types,
        "The \"type\" values read_result reads.");
  bind_writers(m, static_cast<io::ResultDocument*>(nullptr));

  m.def(
      "read_model",
      [](const std::filesystem::path& path) {
        return model_from_document(io::read_json(path), path.string());
      },
      py::arg("path"),
      "The model in a model document (ctid fit --model-output, the files of examples/models): "
      "TransferFunction, AdditiveModel, MimoAdditiveModel, DiscreteTransferFunction or "
      "DelayedFeedbackLoop, chosen by its \"type\". Raises InvalidArgument naming the file "
      "and the field.");
  m.def(
      "model_from_json",
      [](const py::object& document, const std::string& source) {
        const std::string text =
            py::isinstance<py::str>(document)
                ? document.cast<std::string>()
                : py::module_::import("json").attr("dumps")(document).cast<std::string>();
        return model_from_document(io::parse_json(text, source), source);
      },
      py::arg("document"), py::arg("source") = "model",
      "The model of a model document given as a dict or JSON text (as read_model); `source` "
      "names it in error messages.");
  bind_model_writer<TransferFunction>(m);
  bind_model_writer<AdditiveModel>(m);
  bind_model_writer<MimoAdditiveModel>(m);
  bind_model_writer<DiscreteTransferFunction>(m);
  bind_model_writer<DelayedFeedbackLoop>(m);

  m.def(
      "read_csv",
      [](const std::filesystem::path& path, const std::string& time, const std::string& input,
         const std::string& output, const std::optional<std::string>& reference,
         std::optional<double> sample_time, std::optional<double> resample_step,
         const py::object& input_hold, double relative_tolerance) {
        io::CsvColumns columns;
        columns.time = time;
        columns.input = input;
        columns.output = output;
        columns.reference = reference.value_or("");
        columns.relative_tolerance = relative_tolerance;
        return read_csv_record(path, columns, sample_time, resample_step,
                               hold_argument(input_hold));
      },
      py::arg("path"), py::kw_only(), py::arg("time") = "t", py::arg("input") = "u",
      py::arg("output") = "y", py::arg("reference") = py::none(),
      py::arg("sample_time") = py::none(), py::arg("resample") = py::none(),
      py::arg("input_hold") = py::none(), py::arg("relative_tolerance") = 1e-6,
      "A SampledData from a CSV file, read as `ctid fit FILE` reads it (docs/formats.md): "
      "columns by name (time, input, output, optional reference); the uniform step of the time "
      "column is the sample time and its first stamp the start time; sample_time=h overrides "
      "the step (without a time column it is required), resample=h moves irregular stamps onto "
      "a grid of step h; input_hold (Hold, 'zoh' or 'foh') must agree with a '# input_hold:' "
      "line of the file. Raises InvalidArgument naming the file, line or column.");
  m.def(
      "write_csv",
      [](const std::filesystem::path& path, const SampledData& data, const std::string& time,
         const std::string& input, const std::string& output, const std::string& reference,
         bool overwrite) {
        io::CsvColumns columns;
        columns.time = time;
        columns.input = input;
        columns.output = output;
        columns.reference = reference;
        io::write_sampled_data(path, data, columns,
                               overwrite ? io::Overwrite::yes : io::Overwrite::no);
      },
      py::arg("path"), py::arg("data"), py::kw_only(), py::arg("time") = "t",
      py::arg("input") = "u", py::arg("output") = "y", py::arg("reference") = "r",
      py::arg("overwrite") = false,
      "Writes a SampledData as CSV (t,u,y[,r], every value to 17 digits, a '# input_hold: foh' "
      "line for a first-order-hold input), which read_csv reads back bit for bit.");

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

// Python bindings of the study layer: the replayable Monte Carlo helpers (seed hash, sizes,
// MSE summaries) and the Section 6 studies of González et al. (setups, single runs, the whole
// study). Long runs release the GIL. Options and records pickle (a tuple of their fields, arrays
// copied bit for bit), so a study's cases can run in other processes (ctid.study on Dask).
#include <string>
#include <type_traits>

#include "common.h"
#include "ctid/study/monte_carlo.h"
#include "ctid/study/paper_study.h"
#include "ctid/study/study_output.h"
#include "fields.h"

namespace ctid::python {
namespace {

/// Pickling of a struct that lists its fields: the state is the tuple of its field values as
/// Python objects (NumPy arrays for Eigen vectors, so doubles travel bit for bit, NaNs included);
/// unpickling starts from the defaults and casts each value back. No validation: the state is
/// what a pickled object held.
template <HasFields S, class Class>
void add_pickle(Class& cls) {
  cls.def(py::pickle(
      [](const S& self) {
        py::list state;
        for_each_field<S>([&](const auto& f) { state.append(py::cast(self.*(f.member))); });
        return py::tuple(state);
      },
      [](const py::tuple& state) {
        const std::size_t count = field_names<S>().size();
        if (state.size() != count) {
          throw InvalidArgument(std::string(S::type_name) + ": a pickled state has " +
                                std::to_string(state.size()) + " values; expected " +
                                std::to_string(count));
        }
        S object;
        std::size_t i = 0;
        for_each_field<S>([&](const auto& f) {
          using T = std::remove_cvref_t<decltype(object.*(f.member))>;
          object.*(f.member) = state[i++].template cast<T>();
        });
        return object;
      }));
}

}  // namespace

void bind_study(py::module_& m) {
  m.def("splitmix64", &splitmix64, py::arg("x"), "One splitmix64 step.");
  m.def("run_seed", &run_seed, py::arg("study_seed"), py::arg("size_index"), py::arg("run_index"),
        "Seed of one Monte Carlo run.");
  m.def("stream_seed", &stream_seed, py::arg("seed"), py::arg("stream"),
        "Independent stream of a run.");
  m.def("log_spaced_sizes", &log_spaced_sizes, py::arg("first"), py::arg("last"), py::arg("count"),
        "Rounded geometric sequence of sample sizes.");
  bind_result<ErrorSummary>(m, "MSE, bias and predicted MSE of one parameter.");
  m.def("summarize_errors", &summarize_errors, py::arg("estimates"), py::arg("truth"),
        py::arg("predicted_variances") = Eigen::VectorXd(), "MSE summary of estimates.");
  m.def("log_log_slope", &log_log_slope, py::arg("samples"), py::arg("mse"),
        "Slope of log10 MSE against log10 N (-1 for 1/N).");

  bind_enum<StudyKind>(m, "StudyKind", "Which Section 6 study.");
  bind_enum<StudyEstimator>(m, "StudyEstimator", "Estimators compared in a study.");
  auto options_class = bind_options<StudyOptions>(m, "Options of a Section 6 Monte Carlo study.");
  options_class
      .def_static("paper", &StudyOptions::paper, py::arg("kind"), "The paper's study at full size.")
      .def("active_estimators", &StudyOptions::active_estimators, "Estimators that run.");
  add_pickle<StudyOptions>(options_class);
  py::class_<StudySetup>(m, "StudySetup", "True system and experiment of a study.")
      .def_readonly("system", &StudySetup::system, "True AdditiveModel.")
      .def_readonly("sample_time", &StudySetup::sample_time, "h [s].")
      .def_readonly("controller", &StudySetup::controller, "Controller or None.")
      .def_readonly("noise_filter", &StudySetup::noise_filter, "Noise filter or None.")
      .def_readonly("noise_variance", &StudySetup::noise_variance, "Noise variance.")
      .def_readonly("parameter_names", &StudySetup::parameter_names, "Compared parameters.")
      .def_readonly("true_parameters", &StudySetup::true_parameters, "Their true values.");
  m.def("study_setup", &study_setup, py::arg("kind"), "The setup of a study kind.");
  py::class_<StudyRunInput>(m, "StudyRunInput", "Data and start of one run.")
      .def_readonly("data", &StudyRunInput::data, "SampledData.")
      .def_readonly("initial_model", &StudyRunInput::initial_model, "Start.");
  m.def("simulate_study_run", &simulate_study_run, py::arg("options"), py::arg("samples"),
        py::arg("seed"), "Simulate one run from its seed.");
  auto record = bind_result<StudyRecord>(m, "One estimator's outcome in one run.");
  add_pickle<StudyRecord>(record);
  m.def("compared_parameters", &compared_parameters, py::arg("kind"), py::arg("model"),
        "Compared parameters of a model in the study's structure.");
  m.def("run_study_case", &run_study_case, py::arg("options"), py::arg("size_index"),
        py::arg("run_index"), py::call_guard<py::gil_scoped_release>(),
        "Every active estimator on one run (replayable).");
  auto mse_row = bind_result<MseRow>(m, "MSE of one estimator and parameter at one N.");
  add_pickle<MseRow>(mse_row);
  auto result = bind_result<StudyResult>(m, "Records and MSE table of a study.");
  add_pickle<StudyResult>(result);
  bind_result<ParameterTrend>(m, "Trend of one estimator and parameter over the sample sizes.");
  bind_result<StudySummary>(m, "What a study found: MSE table and trends (no per-run records).");
  m.def("parameter_trends", &parameter_trends, py::arg("result"),
        "Log-log slope, MSE over prediction and over srivc per estimator and parameter.");
  m.def("study_summary", &study_summary, py::arg("result"),
        "The StudySummary of a finished study (what `ctid study` writes to summary.json).");
  m.def("summarize_study", &summarize_study, py::arg("records"), py::arg("sample_sizes"),
        py::arg("estimators"), py::arg("true_parameters"), "MSE rows from records.");
  m.def("study_result_from_records", &study_result_from_records, py::arg("options"),
        py::arg("records"),
        "The StudyResult of cases run elsewhere, assembled as run_study assembles its own "
        "(records in the study's order: size, run, estimator).");
  m.def(
      "run_study",
      [](const std::optional<StudyOptions>& options, const py::kwargs& kwargs) {
        const StudyOptions o = options_from<StudyOptions>("run_study", options, kwargs);
        py::gil_scoped_release release;
        return run_study(o);
      },
      py::arg("options") = py::none(), "The whole study in parallel; options as keywords.");
}

}  // namespace ctid::python
